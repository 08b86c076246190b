/* gi_relight: the `gi relight` command (server/gi_main.c dispatches). */
#ifndef GI_RELIGHT_H
#define GI_RELIGHT_H

/* argv[0] is "gi", argv[1] "relight". Returns the exit status. */
int gi_relight_main(int argc, char **argv);

/* `gi validate [JOB.json] EMISSIONS.json`: the emissions file checked as
 * relight reads it and, with the radiosity job, its names against the
 * job's scene (which relight checks against the factorization). Says what
 * it found; returns the exit status. */
int gi_relight_validate(const char *job_path, const char *emissions_path);

#endif
