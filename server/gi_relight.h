/* gi_relight: the `gi relight` command (server/gi_main.c dispatches). */
#ifndef GI_RELIGHT_H
#define GI_RELIGHT_H

/* argv[0] is "gi", argv[1] "relight". Returns the exit status. */
int gi_relight_main(int argc, char **argv);

#endif
