/* token_cmd.h — `isomeshd token add|remove|list`: the administrator's commands for the bearer
 * tokens file (tokens.h). */
#ifndef ISMD_TOKEN_CMD_H
#define ISMD_TOKEN_CMD_H

/* argv[0] is "token". Returns the exit status (0 done, 1 failed, 2 bad usage). */
int ismd_token_command(int argc, char **argv);

#endif
