/* Allocation failures: the i-th allocation fails, for every i, in each phase of a run.
 *
 * tests/alloc.h interposes malloc, calloc, realloc and free (chained to glibc's, or to
 * AddressSanitizer's in the sanitizer build), counts the calls made while a phase runs and
 * returns NULL for exactly one of them (errno ENOMEM). Every allocation counts, whoever makes
 * it: Appell, libyaml, SUNDIALS, glibc.
 *
 * Phases, on a rolling disk with expressions (a constant, 60*deg, and an applied force of t):
 *   load       ap_scene_load_string + ap_scene_initial_state + ap_scene_free
 *   minimal, projected, plain, dae: ap_sim_create in that mode (dopri5: ARKODE; DAE: IDA),
 *              ap_sim_advance over 0.2 s with an output row every 0.05 s, ap_sim_free, on a
 *              scene loaded before the phase
 *   bdf        the same in minimal mode with CVODE's BDF, over 4 ms (its difference-quotient
 *              Jacobian allocates at every evaluation)
 *   sweep      ap_batch_create and a plan of two runs (ap_batch_run_plan_events): a run that
 *              cannot allocate is a row with status AP_ERR_NOMEM and a message
 *   first      a sweep of one run, counted from ap_batch_run_plan_events, in processes that
 *              hold no SUNDIALS context and no ARKODE table yet (the other phases' children
 *              inherit those their parent made when it counted): the contexts reserved before
 *              the runs (a failure there: AP_ERR_NOMEM and a message, no run started) and the
 *              first load of a Butcher table
 * A phase's allocations are counted once (N); then for i = 1 .. N a child process (fork)
 * runs the phase with allocation i failing and reports how it ended:
 *   nomem   a call returned AP_ERR_NOMEM with a message (the required outcome)
 *   ok      the run completed: the failed allocation was not needed (e.g. a cache)
 *   other   a call returned another status (a failure reported as something else)
 *   crash   a signal or a sanitizer report; its stack is printed
 *   exit    the process exited by itself (a library calling exit)
 * The test fails on any "other", "exit", "nomem" without a message, and on any crash but those
 * at the few sites inside SUNDIALS 6.4.1 that Appell cannot reach (known_site: reported with
 * their stacks and tolerated, docs/design.md "Allocation failures"); every vector SUNDIALS
 * clones comes from a pool allocated, and checked, when the integrator is created, and SUNDIALS
 * contexts are reused, never freed (lib/integrate/sunctx.c). Under the sanitizers a
 * child ends through exit(), so LeakSanitizer checks each error path: a leak of a block that
 * libyaml or SUNDIALS allocated for itself is tolerated and counted, any other fails. */
#define _GNU_SOURCE
#include <execinfo.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "appell/appell.h"

/* ---- the injector (alloc.h) ------------------------------------------------------------ */

void __lsan_disable(void) __attribute__((weak));   /* the sanitizer build's LeakSanitizer */
void __lsan_enable(void) __attribute__((weak));

#include "alloc.h"

static void *site[32];          /* the stack of the failed call */
static int nsite = 0;

/* Called at the failing allocation: its stack, on stderr for the parent. */
static void at_failure(void) {
  long keep = ap_alloc_countdown;
  nsite = backtrace(site, 32);   /* may allocate (first use): nothing fails meanwhile */
  ap_alloc_countdown = keep;
  static const char at[] = "the failed allocation:\n";
  (void)!write(2, at, sizeof at - 1);
  backtrace_symbols_fd(site, nsite, 2);
}

/* ---- the phases ----------------------------------------------------------------------------- */

/* A rolling disk (plane contact, quaternion, two rolling rows, gravity, an applied force). */
static const char SCENE[] =
    "name: alloc\n"
    "bodies:\n  disk: {mass: 1.0, shape: {kind: disk, radius: 0.5}, inertia: uniform}\n"
    "joints:\n  disk: {kind: plane_contact}\n"
    "constraints:\n  roll: {kind: rolling, body: disk}\n"
    "effects:\n  gravity: {kind: gravity, g: [0, 0, -9.81]}\n"
    "  push: {kind: applied, body: disk, force: [0.2*sin(3*t), 0, 0.1*exp(-t)]}\n"
    "initial:\n  disk: {x: 0, y: 0, heading: 0, tilt: 60*deg, spin: 0,\n"
    "    spin_rate: -6.0, heading_rate: 4.0, tilt_rate: 0}\n"
    "simulation: {rtol: 1e-8, atol: 1e-10, t_end: 0.2}\n"
    "output:\n  interval: 0.05\n"
    "  channels: [coordinates, speeds, angles, contacts, energy, residual, reactions]\n";

typedef struct phase {
  const char *name;
  ap_mode mode;
  const char *method;        /* NULL: the load phase */
  double interval;           /* output interval (s); 4 outputs */
  int fresh;                 /* 1: counted and run in processes that hold no SUNDIALS context
                                and no ARKODE table yet (the first sweep of a process) */
} phase;

/* CVODE's dense difference-quotient Jacobian allocates three times per evaluation: the BDF
 * phase runs 4 x 1 ms (about 240 allocations) instead of 4 x 50 ms (11000). */
static const phase PHASES[] = {
    {"load", AP_MODE_MINIMAL, NULL, 0.0, 0},
    {"first", AP_MODE_MINIMAL, "sweep", 0.0, 1},   /* before any phase that simulates */
    {"minimal", AP_MODE_MINIMAL, "dopri5", 0.05, 0},
    {"projected", AP_MODE_PROJECTED, "dopri5", 0.05, 0},
    {"plain", AP_MODE_PLAIN, "dopri5", 0.05, 0},
    {"dae", AP_MODE_DAE, "dopri5", 0.05, 0},
    {"bdf", AP_MODE_MINIMAL, "bdf", 0.001, 0},
    {"sweep", AP_MODE_MINIMAL, "sweep", 0.0, 0},
};
enum { NPHASE = sizeof PHASES / sizeof PHASES[0] };

typedef struct outcome {
  int rc;                    /* the first status that was not AP_OK */
  const char *call;          /* the call that returned it */
  char msg[512];
} outcome;

static int load(ap_scene **sc, outcome *o) {
  o->call = "ap_scene_load_string";
  return o->rc = ap_scene_load_string(SCENE, sizeof SCENE - 1, "alloc.yaml", NULL, 0, sc, o->msg,
                                      sizeof o->msg);
}

/* The load phase. */
static void run_load(outcome *o) {
  ap_scene *sc = NULL;
  double q[16], v[16];
  if (load(&sc, o) != AP_OK) return;
  o->call = "ap_scene_initial_state";
  o->rc = ap_scene_initial_state(sc, q, v, NULL, 0, o->msg, sizeof o->msg);
  ap_scene_free(sc);
}

/* A simulation phase on a loaded scene: create, advance with output rows, free. */
static void run_sim(const phase *p, ap_scene *sc, const double *q0, const double *v0,
                    outcome *o) {
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  run.sim.mode = p->mode, run.sim.method = p->method;
  ap_sim *s = NULL;
  double row[64];
  o->call = "ap_sim_create";
  o->rc = ap_sim_create(ap_scene_model(sc), &run.sim, 0.0, q0, v0, &s, o->msg, sizeof o->msg);
  for (int i = 1; o->rc == AP_OK && i <= 4; i++) {
    o->call = "ap_sim_advance";
    o->rc = ap_sim_advance(s, p->interval * i);
    if (o->rc != AP_OK) {
      snprintf(o->msg, sizeof o->msg, "%s", ap_sim_message(s));
      break;
    }
    o->call = "ap_scene_output_row";
    o->rc = ap_scene_output_row(sc, s, row);
  }
  ap_sim_free(s);
}

/* A batch of the scene and a plan over the disk's mass (grid "bodies.disk.mass=A:B:N"). */
typedef struct sweep_case {
  ap_batch *b;
  ap_plan *p;
} sweep_case;

static int sweep_setup(sweep_case *w, const char *grid, outcome *o) {
  static const char *const sets[] = {"simulation.t_end=0.1"};
  ap_batch_def def = ap_batch_def_default();
  o->call = "ap_batch_create";
  o->rc = ap_batch_create(SCENE, sizeof SCENE - 1, "alloc.yaml", sets, 1, &def, &w->b, o->msg,
                          sizeof o->msg);
  if (o->rc == AP_OK && (o->call = "ap_plan_create", o->rc = ap_plan_create(&w->p)) != AP_OK)
    snprintf(o->msg, sizeof o->msg, "out of memory (ap_plan_create has no message)");
  if (o->rc == AP_OK)
    o->call = "ap_plan_add_grid", o->rc = ap_plan_add_grid(w->p, grid, o->msg, sizeof o->msg);
  if (o->rc == AP_OK && ap_batch_ncols(w->b) > 64) o->rc = AP_ERR_INTERNAL;
  return o->rc;
}

/* The plan's runs (at most 2; ap_batch_run_plan_events, one worker thread). A failed
 * allocation inside a run must leave that run a row with status AP_ERR_NOMEM and a message,
 * the batch going on; one before the runs, AP_ERR_NOMEM with a message in the first. */
static void sweep_go(sweep_case *w, outcome *o) {
  long count = ap_plan_count(w->p);
  double vals[2 * 64];
  int status[2] = {0, 0};
  char *msgs[2] = {NULL, NULL}, *evs[2] = {NULL, NULL};
  o->call = "ap_batch_run_plan_events";
  o->rc = count > 2 ? AP_ERR_INTERNAL
                    : ap_batch_run_plan_events(w->b, w->p, 0, count, vals, status, msgs, evs);
  if (o->rc == AP_ERR_NOMEM) snprintf(o->msg, sizeof o->msg, "%s", msgs[0] ? msgs[0] : "");
  for (int i = 0; i < count && o->rc == AP_OK; i++)
    if (status[i] != AP_OK) {
      o->call = "a run of the batch", o->rc = status[i];
      snprintf(o->msg, sizeof o->msg, "%s", msgs[i] ? msgs[i] : "");
    }
  ap_batch_messages_free(2, msgs);
  ap_batch_messages_free(2, evs);
}

static void sweep_free(sweep_case *w) {
  ap_plan_free(w->p);
  ap_batch_free(w->b);
}

/* The sweep phase: batch, plan of two runs and the runs, all counted. */
static void run_sweep(outcome *o) {
  sweep_case w = {NULL, NULL};
  if (sweep_setup(&w, "bodies.disk.mass=1:2:2", o) == AP_OK) sweep_go(&w, o);
  sweep_free(&w);
}

/* Runs phase p with allocation fail (1-based; -1: none) failing; returns the count. */
static long run_phase(const phase *p, long fail, outcome *o) {
  ap_scene *sc = NULL;
  double q0[16], v0[16];
  memset(o, 0, sizeof *o);
  int sweep = p->method && strcmp(p->method, "sweep") == 0;
  sweep_case w = {NULL, NULL};
  if (p->fresh && sweep_setup(&w, "bodies.disk.mass=1:1:1", o) != AP_OK) {   /* not counted */
    sweep_free(&w);
    return -1;
  }
  if (p->method && !sweep) {   /* load outside the count */
    if (load(&sc, o) != AP_OK ||
        ap_scene_initial_state(sc, q0, v0, NULL, 0, o->msg, sizeof o->msg) != AP_OK) {
      o->call = "setup";
      o->rc = AP_ERR_INTERNAL;
      ap_scene_free(sc);
      return -1;
    }
  }
  long before = n_alloc;
  ap_alloc_on_fail = at_failure;
  ap_alloc_fail_at(fail > 0 ? fail - 1 : -1);
  if (p->fresh) sweep_go(&w, o);
  else if (sweep) run_sweep(o);
  else if (p->method) run_sim(p, sc, q0, v0, o);
  else run_load(o);
  ap_alloc_fail_at(-1);
  long n = n_alloc - before;
  ap_scene_free(sc);
  sweep_free(&w);
  return n;
}

/* run_phase without failures in a child, for a fresh phase: this process keeps no SUNDIALS
 * context or ARKODE table from it, so the children of its cases start without them. */
static long count_fresh(const phase *p, outcome *o) {
  int fd[2];
  long n = -1;
  if (pipe(fd) != 0) return -1;
  fflush(NULL);
  pid_t pid = fork();
  if (pid == 0) {
    close(fd[0]);
    n = run_phase(p, -1, o);
    (void)!write(fd[1], &n, sizeof n);
    (void)!write(fd[1], o, sizeof *o);
    _exit(0);
  }
  close(fd[1]);
  if (pid < 0 || read(fd[0], &n, sizeof n) != sizeof n || read(fd[0], o, sizeof *o) != sizeof *o)
    n = -1;
  close(fd[0]);
  if (pid > 0) waitpid(pid, NULL, 0);
  return n;
}

/* ---- children --------------------------------------------------------------------------- */

static void on_signal(int sig) {
  static const char head[] = "crashed: signal\n";
  void *frames[32];
  int n = backtrace(frames, 32);
  (void)!write(2, head, sizeof head - 1);
  backtrace_symbols_fd(frames, n, 2);
  signal(sig, SIG_DFL);
  raise(sig);
}

enum { END_OK = 0, END_NOMEM = 10, END_NOMEM_SILENT = 11, END_OTHER = 12 };

/* The child's body: run the phase with allocation i failing, report on stdout, exit. */
static void child(const phase *p, long i) {
  signal(SIGSEGV, on_signal), signal(SIGBUS, on_signal), signal(SIGABRT, on_signal);
  signal(SIGFPE, on_signal), signal(SIGILL, on_signal);
  alarm(60);
  outcome o;
  run_phase(p, i, &o);
  int end = o.rc == AP_OK ? END_OK : o.rc != AP_ERR_NOMEM ? END_OTHER
            : o.msg[0] ? END_NOMEM : END_NOMEM_SILENT;
  if (end != END_OK) printf("status: %s -> %d (%s): %s\n", o.call, o.rc, ap_strerror(o.rc),
                            o.msg);
  fflush(stdout);
  exit(end);   /* through exit(): LeakSanitizer checks the error path in the sanitizer build */
}

/* Runs case i of phase p in a child; returns its report (stdout and stderr, malloc'd by the
 * next allocator, NULL when none) and how it ended: an END_* code, -signal, or 100 + status
 * for another exit status. */
static char *run_child(const phase *p, long i, int *end) {
  int fd[2];
  if (pipe(fd) != 0) return NULL;
  fflush(NULL);
  pid_t pid = fork();
  if (pid == 0) {
    close(fd[0]);
    dup2(fd[1], 1), dup2(fd[1], 2);
    child(p, i);
  }
  close(fd[1]);
  size_t cap = 1 << 16, len = 0;
  char *buf = malloc(cap), sink[4096];
  ssize_t got;
  while ((got = read(fd[0], buf && len + 1 < cap ? buf + len : sink,
                     buf && len + 1 < cap ? cap - 1 - len : sizeof sink)) > 0)
    if (buf && len + 1 < cap) len += (size_t)got;   /* the rest is read and dropped */
  close(fd[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  if (buf) buf[len] = '\0';
  if (WIFSIGNALED(status)) *end = -WTERMSIG(status);
  else {
    int x = WEXITSTATUS(status);
    *end = x == END_OK || x == END_NOMEM || x == END_NOMEM_SILENT || x == END_OTHER ? x
                                                                                 : 100 + x;
  }
  return buf;
}

/* ---- reading the reports ---------------------------------------------------------------- */

/* The function a stack line names: "lib(func+0x..)" (glibc), "in func " (sanitizers), or
 * addr2line's answer for an address inside this program; "" for frames not worth naming
 * (this test's wrappers and handler, libc, the sanitizer runtime). */
static void frame_name(const char *line, const char *exe, char *out, size_t len) {
  out[0] = '\0';
  const char *in = strstr(line, " in ");
  if (in && strstr(line, "#")) {   /* "#3 0x... in func (/path+0x...)" */
    sscanf(in + 4, "%127s", out);
  } else {
    const char *lp = strchr(line, '('), *plus = lp ? strchr(lp, '+') : NULL;
    if (!lp || !plus) return;
    if (plus > lp + 1) snprintf(out, len, "%.*s", (int)(plus - lp - 1), lp + 1);
    else if (strstr(line, "test_alloc(")) {   /* a hidden function of Appell: ask addr2line */
      static char offs[256][24], names[256][64];
      static int ncache = 0;
      char cmd[1024], off[24] = "";
      sscanf(plus + 1, "%23[0-9a-fx]", off);
      int hit = -1;
      for (int i = 0; i < ncache && hit < 0; i++)
        if (!strcmp(offs[i], off)) hit = i;
      if (hit >= 0) snprintf(out, len, "%s", names[hit]);
      snprintf(cmd, sizeof cmd, "addr2line -f -e '%s' %s 2>/dev/null", exe, off);
      FILE *f = hit >= 0 ? NULL : popen(cmd, "r");
      if (f) {
        if (!fgets(out, (int)len, f)) out[0] = '\0';
        pclose(f);
        out[strcspn(out, "\n")] = '\0';
      }
      if (!out[0] || !strcmp(out, "??")) snprintf(out, len, "appell+%s", off);   /* unnamed */
      if (hit < 0 && ncache < 256) {
        snprintf(offs[ncache], sizeof offs[ncache], "%s", off);
        snprintf(names[ncache++], sizeof names[0], "%s", out);
      }
    }
  }
  const char *slash = strrchr(out, '/');   /* an unnamed frame of a library: its file name */
  if (slash) memmove(out, slash + 1, strlen(slash));
  static const char *const skip[] = {"malloc", "calloc", "realloc", "inject", "on_signal",
                                     "at_failure", "ap_alloc_", "ap_next_",
                                     "__interceptor", "__libc", "raise", "abort", "__GI",
                                     "__sanitizer", "__asan", "__ubsan", "backtrace", NULL};
  for (int i = 0; skip[i]; i++)
    if (strncmp(out, skip[i], strlen(skip[i])) == 0) out[0] = '\0';
}

/* Up to `want` named frames of the stack that follows `start` in the report, "a < b < c". */
static void stack_names(const char *start, const char *exe, int want, char *out, size_t len) {
  out[0] = '\0';
  int got = 0;
  for (const char *s = start; s && *s && got < want;) {
    const char *e = strchr(s, '\n');
    char line[512], name[128];
    snprintf(line, sizeof line, "%.*s", (int)(e ? e - s : (long)strlen(s)), s);
    if (s != start && (strncmp(line, "the failed allocation", 21) == 0 ||
                       strstr(line, "Sanitizer") || strncmp(line, "crashed", 7) == 0))
      break;
    frame_name(line, exe, name, sizeof name);
    if (name[0] && strcmp(name, "main") != 0) {
      size_t l = strlen(out);
      snprintf(out + l, len - l, "%s%s", got ? " < " : "", name);
      got++;
    }
    s = e ? e + 1 : NULL;
  }
}

/* A one-line description of how a case ended, the same for cases that failed alike. */
static void signature(int end, const char *rep, const char *exe, char *out, size_t len) {
  char crash[512] = "", site_[512] = "", status[256] = "";
  const char *st = strstr(rep, "status: "), *fa = strstr(rep, "the failed allocation:\n");
  const char *cr = strstr(rep, "crashed: signal\n"), *san = strstr(rep, "Sanitizer: ");
  const char *leak = strstr(rep, "LeakSanitizer"), *from = leak ? strstr(leak, "from:\n") : NULL;
  if (st) {   /* the status line, numbers dropped */
    size_t j = 0;
    for (const char *c = st + 8; *c && *c != '\n' && j + 1 < sizeof status; c++)
      if (!(*c >= '0' && *c <= '9') || c == st + 8) status[j++] = *c;
    status[j] = '\0';
  }
  if (fa) stack_names(fa + 23, exe, 3, site_, sizeof site_);
  if (cr) stack_names(cr + 16, exe, 3, crash, sizeof crash);
  else if (san) {
    char kind[96] = "";
    sscanf(san + 11, "%95s", kind);
    const char *f0 = strstr(san, "#0 ");
    stack_names(f0 ? f0 : san, exe, 3, crash, sizeof crash);
    snprintf(crash + strlen(crash), sizeof crash - strlen(crash), " [%s]", kind);
  }
  if (from) {   /* a leak on the error path: where the leaked block was allocated */
    stack_names(from + 6, exe, 3, crash, sizeof crash);
    snprintf(out, len, "%s | leak allocated in %s | failed allocation in %s", status,
             crash[0] ? crash : "?", site_[0] ? site_ : "?");
  } else if (end < 0 || cr || san)
    snprintf(out, len, "crash in %s | failed allocation in %s", crash[0] ? crash : "?",
             site_[0] ? site_ : "?");
  else if (end >= 100)
    snprintf(out, len, "exit(%d) | failed allocation in %s", end - 100, site_[0] ? site_ : "?");
  else
    snprintf(out, len, "%s | failed allocation in %s", status, site_[0] ? site_ : "?");
}

/* 1 when name is a SUNDIALS function (ARKode, CVode, IDA, N_V, SUN*, or an unnamed frame of
 * libsundials). */
static int sundials_name(const char *name) {
  static const char *const pre[] = {"ARK", "ark", "ERKStep", "erkStep", "CVode", "cv", "IDA",
                                    "ida", "N_V", "SUN", "Sun", "sun", "Dense", "dense",
                                    "libsundials", NULL};
  for (int i = 0; pre[i]; i++)
    if (strncmp(name, pre[i], strlen(pre[i])) == 0) return 1;
  return 0;
}

/* 1 when the crash's innermost named frame is in SUNDIALS. */
static int in_sundials(const char *sig) {
  return strncmp(sig, "crash in ", 9) == 0 && sundials_name(sig + 9);
}

/* 1 when a SUNDIALS crash is at one of the sites Appell cannot reach (SUNDIALS 6.4.1 uses the
 * result of a failed allocation inside one call): the context's logger (SUNLogger_Create),
 * ARKODE's Butcher table loader, erkStep_Init's stage array (arkAllocVec writing into it).
 * Every vector SUNDIALS clones comes from a pool allocated at creation
 * (lib/integrate/nvpool.c) and CVODE's matrix clone is made at creation, so a crash in
 * N_VClone, N_VCloneEmpty, N_VDestroy or SUNMatClone is a defect. Contexts are created once and
 * reused, never freed (lib/integrate/sunctx.c), and Butcher tables loaded once per process
 * (stepper_arkode.c): their sites are reached by the first integrators of a process only (the
 * phase "first"). erkStep_Init runs when the stepper is created (stepper_arkode.c,
 * ark_first_setup), before the run has any state. */
static int known_site(const char *sig) {
  static const char *const site_[] = {"crash in SUNLogger_", "crash in ARKodeButcherTable_",
                                      "crash in arkAllocVec < erkStep_Init", NULL};
  /* Under the sanitizers the innermost frame may be a SUNDIALS library without a name
   * ("crash in libsundials_arkode.so.5 < SUNLogger_Destroy < ..."): the next frame names the
   * site. */
  char inner[640];
  const char *next = strstr(sig, " < ");
  if (strncmp(sig, "crash in libsundials", 20) == 0 && next) {
    snprintf(inner, sizeof inner, "crash in %s", next + 3);
    sig = inner;
  }
  for (int i = 0; site_[i]; i++)
    if (strncmp(sig, site_[i], strlen(site_[i])) == 0) return 1;
  return 0;
}

/* 1 when the sanitizer runtime itself stopped (its CHECK) because an allocation glibc makes for
 * it failed: AddressSanitizer asks pthread_getattr_np for a new thread's stack bounds, and
 * that call's allocation was the one made to fail. The path exists only in the sanitizer
 * build; Appell's pool reports the same failure as AP_ERR_NOMEM in the plain build. */
static int sanitizer_runtime(const char *sig) {
  return strstr(sig, "[CHECK]") != NULL && strstr(sig, "| failed allocation in pthread_") != NULL;
}

/* 1 for a leak (sanitizer build) of a block that libyaml or SUNDIALS allocated for itself and
 * lost on its own error path (libyaml 0.2.5's loader, ERKStepCreate freeing nothing when a
 * later allocation fails): the returned status was right, nothing was handed to Appell. */
static int leak_inside(const char *sig) {
  const char *p = strstr(sig, "| leak allocated in ");
  if (!p) return 0;
  p += 20;
  return strncmp(p, "yaml_", 5) == 0 || strncmp(p, "libyaml", 7) == 0 || sundials_name(p);
}

/* Distinct outcomes of a phase with their counts. */
typedef struct group { char sig[640]; long count, first; int kind; } group;
#define MAXGROUP 64

int main(int argc, char **argv) {
  const char *only_phase = NULL;
  long only_case = 0;
  int count_only = 0;
  for (int i = 1; i < argc; i++)   /* --phase NAME, --case I: run one and show it */
    if (!strcmp(argv[i], "--phase") && i + 1 < argc) only_phase = argv[++i];
    else if (!strcmp(argv[i], "--case") && i + 1 < argc) only_case = atol(argv[++i]);
    else if (!strcmp(argv[i], "--count")) count_only = 1;
  int failed = 0;
  /* Load libgcc's unwinder before anything is counted. LeakSanitizer takes the loader's blocks
   * for reachable only when the loader calls malloc itself, not through alloc.h's wrapper:
   * the loading is kept out of its sight. */
  void *warm[1];
  if (__lsan_disable) __lsan_disable();
  backtrace(warm, 1);
  if (__lsan_enable) __lsan_enable();
  setvbuf(stdout, NULL, _IOLBF, 0);
  static group groups[MAXGROUP];
  for (int ph = 0; ph < NPHASE; ph++) {
    const phase *p = &PHASES[ph];
    if (only_phase && strcmp(only_phase, p->name) != 0) continue;
    outcome o;
    long n = p->fresh ? count_fresh(p, &o) : run_phase(p, -1, &o);
    if (n < 0 || o.rc != AP_OK) {
      printf("%s: the run without failures failed: %s -> %d: %s\n", p->name, o.call, o.rc,
             o.msg);
      failed++;
      continue;
    }
    if (count_only) {
      printf("%-9s %5ld allocations\n", p->name, n);
      continue;
    }
    /* nomem, completed, crashed inside SUNDIALS, wrong, nomem with a leak inside libyaml, the
     * sanitizer runtime stopped */
    long count[6] = {0, 0, 0, 0, 0, 0};
    int ng = 0;
    for (long i = only_case ? only_case : 1; i <= (only_case ? only_case : n); i++) {
      int end = 0;
      char *rep = run_child(p, i, &end), sig[640];
      if (only_case) printf("%s", rep ? rep : "");
      int k = end == END_NOMEM ? 0 : end == END_OK ? 1 : 3;
      if (k == 3) {
        signature(end, rep ? rep : "", argv[0], sig, sizeof sig);
        if (in_sundials(sig) && known_site(sig)) k = 2;
        else if (sanitizer_runtime(sig)) k = 5;
        else if (leak_inside(sig) && strstr(sig, "(out of memory)")) k = 4;
        int g = 0;
        while (g < ng && strcmp(groups[g].sig, sig) != 0) g++;
        if (g == ng && ng < MAXGROUP) {
          snprintf(groups[g].sig, sizeof groups[g].sig, "%s", sig);
          groups[g].count = 0, groups[g].first = i, groups[g].kind = k, ng++;
        }
        if (g < ng) groups[g].count++;
      }
      count[k]++;
      free(rep);
    }
    printf("%-9s %5ld allocations failed one at a time: %5ld AP_ERR_NOMEM, %4ld completed, "
           "%ld crashed inside SUNDIALS, %ld stopped the sanitizer runtime, %ld other "
           "(%ld AP_ERR_NOMEM leaked inside a library)\n",
           p->name, n, count[0] + count[4], count[1], count[2], count[5], count[3], count[4]);
    static const char *const label[6] = {"", "", "sundials", "WRONG   ", "leak    ", "runtime "};
    for (int g = 0; g < ng; g++)
      printf("  %s %5ld x (first: allocation %ld) %s\n", label[groups[g].kind], groups[g].count,
             groups[g].first, groups[g].sig);
    failed += (int)count[3];
  }
  printf("test_alloc: %s\n", failed ? "FAILED" : "passed");
  return failed ? 1 : 0;
}
