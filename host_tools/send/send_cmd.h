/* send_cmd.h - `cmz send` (see send_cmd.c). */
#ifndef SEND_CMD_H
#define SEND_CMD_H

/** Run `cmz send` with the arguments after "send". @return the exit status */
int cmz_cmd_send(int argc, char **argv);

#endif /* SEND_CMD_H */
