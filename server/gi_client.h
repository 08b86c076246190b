/* gi_client: the `gi` commands that talk to a farm over its HTTP API:
 *
 *   gi submit JOB.json [--priority N] [--wait] [--out DIR] [--progress MODE]
 *   gi status ID [--json]      gi jobs [--json]      gi workers [--json]
 *   gi wait ID [--out DIR] [--progress MODE]
 *   gi cancel ID               gi fetch ID [--out DIR]
 *
 * Every command takes --farm URL (default $GI_FARM, else
 * http://127.0.0.1:7070) and reads the API token from --token-file FILE,
 * $GI_FARM_TOKEN_FILE or $GI_FARM_TOKEN. */
#ifndef GI_CLIENT_H
#define GI_CLIENT_H

/* 1 if cmd is one of the farm commands. */
int gi_client_is_command(const char *cmd);
/* Runs argv[1] (a farm command); returns the exit status: 0 success, 2
 * invalid input (the job, arguments), 1 other failures, 130 interrupted. */
int gi_client_main(int argc, char **argv);
/* For gi's usage text. */
extern const char gi_client_usage[];

#endif
