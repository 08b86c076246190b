/* gi_thread_call: one function run on a thread of its own, for a loop that
 * must keep answering (gi-farmd) while a file is written or a job finishes:
 * started, asked whether it has ended, joined. Without a thread (none can
 * be started), the function runs before gi_thread_call_start returns. */
#ifndef GI_THREAD_CALL_H
#define GI_THREAD_CALL_H

typedef struct gi_thread_call gi_thread_call;

/* Runs fn(arg) on a new thread. When it has ended, and if wake_fd >= 0,
 * 8 bytes (an eventfd's count of 1) are written to wake_fd, so that a
 * poll() on it wakes up. Never NULL. */
gi_thread_call *gi_thread_call_start(void (*fn)(void *arg), void *arg, int wake_fd);
/* 1 once fn has returned (gi_thread_call_join then does not wait). */
int gi_thread_call_done(const gi_thread_call *c);
/* Waits for fn to return and frees c (NULL: nothing). */
void gi_thread_call_join(gi_thread_call *c);

#endif
