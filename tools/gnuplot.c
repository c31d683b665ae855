/* gnuplot for `appell plot` and `appell linearize --plot` (cli.h): a child gnuplot reads the
 * script from a pipe, its standard output goes to /dev/null (never a figure on the terminal),
 * its messages to our standard error. */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cli.h"

int cli_safe_name(const char *s) { return !strpbrk(s, "'\"\n\r\\"); }

int cli_gnuplot(const char *cmd, void (*script)(FILE *g, const void *user), const void *user) {
  int fd[2];
  if (pipe(fd) != 0) return fprintf(stderr, "appell %s: pipe: %s\n", cmd, CLI_STRERROR(errno)), -1;
  pid_t pid = fork();
  if (pid < 0) {
    close(fd[0]), close(fd[1]);
    return fprintf(stderr, "appell %s: fork: %s\n", cmd, CLI_STRERROR(errno)), -1;
  }
  if (pid == 0) {
    dup2(fd[0], STDIN_FILENO);
    close(fd[0]), close(fd[1]);
    int null = open("/dev/null", O_WRONLY);
    if (null >= 0) dup2(null, STDOUT_FILENO), close(null);
    execlp("gnuplot", "gnuplot", (char *)NULL);
    fprintf(stderr, "appell %s: cannot run gnuplot (%s); install the Debian package "
            "gnuplot-nox\n", cmd, CLI_STRERROR(errno));
    _exit(127);
  }
  close(fd[0]);
  FILE *g = fdopen(fd[1], "w");
  if (g) {
    script(g, user);
    fclose(g);
  } else {
    close(fd[1]);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 127)
      fprintf(stderr, "appell %s: gnuplot failed (status %d)\n", cmd, WEXITSTATUS(status));
    return -1;
  }
  return 0;
}
