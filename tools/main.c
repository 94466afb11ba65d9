/* main.c: the tessera command: a table of subcommands, each in its own
 * file (cmd_*.c). */
#define _POSIX_C_SOURCE 200809L /* sigaction */
#include "cli.h"

#include <signal.h>
#include <string.h>

#ifndef TSR_VERSION
#define TSR_VERSION "0.1.0"
#endif

static const cli_command *const commands[] = {&cli_cmd_info,        &cli_cmd_generate, &cli_cmd_mesh,
                                              &cli_cmd_triangulate, &cli_cmd_check,    &cli_cmd_bench,
                                              &cli_cmd_fly, &cli_cmd_patch};
enum { NCOMMANDS = sizeof commands / sizeof commands[0] };

static void usage(FILE *f)
{
    fprintf(f, "usage: tessera COMMAND [options]\n\n"
               "Tessera turns heightfields and parametric surfaces into watertight triangle meshes.\n\n"
               "commands:\n");
    for (int i = 0; i < NCOMMANDS; i++)
        fprintf(f, "  %-12s %s\n", commands[i]->name, commands[i]->summary);
    fprintf(f, "\n'tessera COMMAND --help' describes a command's options.\n"
               "'tessera --version' prints the version.\n");
}

/* Interrupted (Ctrl-C, a batch system's time limit): the output being
 * written is removed, then the signal does what it would have done. */
static void on_signal(int sig)
{
    tsr_atomic_remove_pending();
    if (cli_signal_cleanup)
        cli_signal_cleanup();
    signal(sig, SIG_DFL);
    raise(sig);
}

int main(int argc, char **argv)
{
    static const int sigs[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT};
    for (size_t k = 0; k < sizeof sigs / sizeof sigs[0]; k++) {
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_signal;
        sigemptyset(&sa.sa_mask);
        struct sigaction old;
        /* (a signal ignored when we start, as nohup leaves SIGHUP, stays so) */
        if (sigaction(sigs[k], NULL, &old) == 0 && old.sa_handler != SIG_IGN)
            sigaction(sigs[k], &sa, NULL);
    }
    if (argc < 2) {
        usage(stderr);
        return CLI_USAGE;
    }
    const char *name = argv[1];
    if (cli_is_help(name) || !strcmp(name, "help")) {
        if (argc >= 3)
            for (int i = 0; i < NCOMMANDS; i++)
                if (!strcmp(argv[2], commands[i]->name)) {
                    commands[i]->help(stdout);
                    return CLI_OK;
                }
        usage(stdout);
        return CLI_OK;
    }
    if (!strcmp(name, "--version") || !strcmp(name, "version")) {
        printf("tessera %s\n", TSR_VERSION);
        return CLI_OK;
    }
    for (int i = 0; i < NCOMMANDS; i++)
        if (!strcmp(name, commands[i]->name))
            return commands[i]->run(argc - 1, argv + 1);
    cli_error(NULL, "unknown command '%s' (see tessera --help)", name);
    return CLI_USAGE;
}
