/* appell run: where the CSV goes, and what a signal does to it (docs/cli.md, "Output files and
 * signals").
 *
 * The target is checked before anything is simulated, by the library's rules (lib/io/outfile.c,
 * include/appell/outfile.h; the Python package uses the same): standard output ("-" or no
 * --out), a FIFO or a device (a symbolic link is followed) are written in place; a directory,
 * a dangling link or the scene file itself (same device and inode, whatever the name) are
 * refused; a regular file (new, or an existing one, through a link too) is written as a
 * temporary file beside it, named FILE.appell-tmp.PID.XXXXXX, and renamed over it after the
 * last row (cli_out_finish with keep: also after a failed or interrupted run, whose rows up to
 * where it stopped are kept, appell run's run record saying why). The new file gets the
 * permissions of the file it replaces, or 0666 minus the umask.
 *
 * Signals: every signal whose default action ends the process and that can be caught gets a
 * handler through sigaction (never reset on delivery). The first one of those that arrive
 * asynchronously (SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE, SIGXFSZ, ...) is recorded, the run
 * stops at the next internal step (cli_interrupted, polled by the library through
 * ap_sim_set_poll); a second one removes the temporary files at once and exits 128 + the
 * signal (repeats of SIGXFSZ and SIGPIPE, which failed writes raise, do not count: the failed
 * write is reported instead). A fault (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP,
 * SIGSYS) removes the temporary files and re-raises with the handler that was there before.
 * SIGKILL cannot be caught: its temporary file stays, and the next run to the same target
 * removes it when the process named in it no longer exists (and the file is a regular file
 * of this user). Invariant: a file at the target path is complete (every row up to where the
 * run stopped), never a fragment cut by a failed write. */
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include <appell/outfile.h>

#include "cli.h"

/* ---- signals ------------------------------------------------------------------------------ */

static volatile sig_atomic_t caught = 0;    /* the first terminating signal, or 0 */
/* The files being written (the CSV, the run record): their temporary files are removed by a
 * second signal or a fault. A slot is set before the file is created and cleared after it is
 * renamed or removed; o->tmp holds the complete name before the file exists. */
#define CLEANUP_SLOTS 4
static ap_outfile *volatile cleanup[CLEANUP_SLOTS];
static struct sigaction previous[65];       /* the actions replaced for faults */

static void remove_temporaries(void) {
  for (int i = 0; i < CLEANUP_SLOTS; i++) {
    ap_outfile *o = cleanup[i];
    if (o && o->tmp[0]) unlink(o->tmp);
  }
}

static void arm(ap_outfile *o, int on) {
  for (int i = 0; i < CLEANUP_SLOTS; i++)
    if (on ? !cleanup[i] : cleanup[i] == o) {
      cleanup[i] = on ? o : NULL;
      return;
    }
}

/* SIGXFSZ and SIGPIPE come from our own writes, once per failed write (a file size limit, a
 * reader gone): the failed write is reported, and their repeats do not count as a second
 * signal. */
static int from_writes(int sig) {
#ifdef SIGXFSZ
  if (sig == SIGXFSZ) return 1;
#endif
  return sig == SIGPIPE;
}

static void on_signal(int sig) {
  if (caught && !from_writes(sig) && !from_writes(caught)) {
    remove_temporaries();   /* the second one: do not wait for the run to notice */
    _exit(128 + sig);
  }
  if (!caught) caught = sig;
}

static void on_fault(int sig) {
  remove_temporaries();
  if (sig > 0 && sig < 65) sigaction(sig, &previous[sig], NULL);
  raise(sig);   /* delivered when this handler returns, with the previous action */
}

static const int async_signals[] = {
    SIGHUP, SIGINT, SIGQUIT, SIGTERM, SIGPIPE, SIGALRM, SIGUSR1, SIGUSR2,
#ifdef SIGXCPU
    SIGXCPU,
#endif
#ifdef SIGXFSZ
    SIGXFSZ,
#endif
#ifdef SIGVTALRM
    SIGVTALRM,
#endif
#ifdef SIGPROF
    SIGPROF,
#endif
#ifdef SIGPOLL
    SIGPOLL,
#endif
#ifdef SIGSTKFLT
    SIGSTKFLT,
#endif
#ifdef SIGPWR
    SIGPWR,
#endif
};

static const int fault_signals[] = {
    SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT,
#ifdef SIGTRAP
    SIGTRAP,
#endif
#ifdef SIGSYS
    SIGSYS,
#endif
};

void cli_signals_install(void) {
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sigfillset(&sa.sa_mask);   /* one handler at a time */
  sa.sa_flags = SA_RESTART;  /* a write to a slow reader goes on; the run stops at its poll */
  sa.sa_handler = on_signal;
  for (size_t i = 0; i < sizeof async_signals / sizeof async_signals[0]; i++)
    sigaction(async_signals[i], &sa, NULL);
#if defined(SIGRTMIN) && defined(SIGRTMAX)
  for (int s = SIGRTMIN; s <= SIGRTMAX; s++) sigaction(s, &sa, NULL);
#endif
  sa.sa_flags = 0;
  sa.sa_handler = on_fault;
  for (size_t i = 0; i < sizeof fault_signals / sizeof fault_signals[0]; i++)
    if (fault_signals[i] < 65) sigaction(fault_signals[i], &sa, &previous[fault_signals[i]]);
}

int cli_interrupted(void) { return caught; }

const char *cli_signal_name(int sig) {
  static const struct {
    int sig;
    const char *name;
  } names[] = {{SIGHUP, "SIGHUP"},   {SIGINT, "SIGINT"},   {SIGQUIT, "SIGQUIT"},
               {SIGTERM, "SIGTERM"}, {SIGPIPE, "SIGPIPE"}, {SIGALRM, "SIGALRM"},
               {SIGUSR1, "SIGUSR1"}, {SIGUSR2, "SIGUSR2"},
#ifdef SIGXCPU
               {SIGXCPU, "SIGXCPU"},
#endif
#ifdef SIGXFSZ
               {SIGXFSZ, "SIGXFSZ"},
#endif
  };
  for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
    if (names[i].sig == sig) return names[i].name;
  static char other[32];
  snprintf(other, sizeof other, "signal %d", sig);
  return other;
}

/* ---- the target (the rules: lib/io/outfile.c) -------------------------------------------- */

/* The subcommand named in messages (appell sweep writes its table through these too). */
static const char *command = "run";

void cli_out_command(const char *name) { command = name; }

int cli_out_check(cli_out *o, const char *target, const char *scene) {
  memset(o, 0, sizeof *o);
  o->file.fd = -1;
  if (!target || strcmp(target, "-") == 0) return o->kind = CLI_OUT_STDOUT, EXIT_OK;
  o->target = target;
  char msg[AP_OUT_PATH_MAX + 300];
  const char *keep[1] = {scene};
  if (ap_out_check(&o->file, target, keep, scene ? 1 : 0, msg, sizeof msg) != AP_OK) {
    const char *input = strstr(msg, ": is the input file ");
    if (input)   /* the only input is the scene */
      fprintf(stderr, "appell %s: --out %s: is the scene file %s; refusing to overwrite it\n",
              command, target, scene);
    else
      fprintf(stderr, "appell %s: --out %s\n", command, msg);
    return EXIT_INPUT;
  }
  o->kind = o->file.kind == AP_OUT_FILE ? CLI_OUT_FILE : CLI_OUT_DIRECT;
  return EXIT_OK;
}

int cli_out_open(cli_out *o) {
  if (o->kind == CLI_OUT_STDOUT) return o->f = stdout, EXIT_OK;
  char msg[AP_OUT_PATH_MAX + 300];
  arm(&o->file, 1);
  if (ap_out_open(&o->file, msg, sizeof msg) != AP_OK) {
    arm(&o->file, 0);
    return fprintf(stderr, "appell %s: %s\n", command, msg), EXIT_INTERNAL;
  }
  if (o->file.note[0]) fprintf(stderr, "appell %s: %s\n", command, o->file.note);
  o->f = fdopen(o->file.fd, "w");
  if (!o->f) {
    int err = errno;
    ap_out_finish(&o->file, 0, NULL, 0);
    arm(&o->file, 0);
    return fprintf(stderr, "appell %s: cannot write %s: %s\n", command, o->file.path,
                   CLI_STRERROR(err)), EXIT_INTERNAL;
  }
  return EXIT_OK;
}

const char *cli_out_name(const cli_out *o) {
  return o->kind == CLI_OUT_STDOUT ? "standard output" : o->file.path;
}

int cli_out_failed(cli_out *o) {
  if (!o->err && o->f && ferror(o->f)) o->err = errno ? errno : EIO;
  return o->err;
}

int cli_out_finish(cli_out *o, int code, int keep) {
  if (!o->f) return code;
  cli_out_failed(o);
  int rc = o->kind == CLI_OUT_STDOUT ? fflush(stdout) : fclose(o->f);
  if (rc != 0 && !o->err) o->err = errno ? errno : EIO;
  o->f = NULL;
  o->file.fd = -1;   /* closed with the FILE */
  if (o->kind == CLI_OUT_STDOUT) clearerr(stdout);   /* reported here, not again at exit */
  if (o->err && o->err != EPIPE)
    fprintf(stderr, "appell %s: writing %s failed: %s%s\n", command, cli_out_name(o),
            CLI_STRERROR(o->err), o->kind == CLI_OUT_FILE ? " (the partial file is removed)" : "");
  if (o->err && code == EXIT_OK)
    code = o->err == EPIPE ? 128 + SIGPIPE : EXIT_INTERNAL;
  if (o->kind != CLI_OUT_FILE) return code;
  char msg[2 * AP_OUT_PATH_MAX + 300];
  keep = !o->err && (code == EXIT_OK || keep);
  if (ap_out_finish(&o->file, keep, msg, sizeof msg) != AP_OK) {
    fprintf(stderr, "appell %s: %s\n", command, msg);
    code = EXIT_INTERNAL;
  }
  arm(&o->file, 0);
  return code;
}

int cli_out_close(cli_out *o, int code) { return cli_out_finish(o, code, code == EXIT_OK); }
