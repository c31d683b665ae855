/* Appell: scene files.
 *
 * A scene is a YAML file that describes bodies, joints, constraints, effects, the initial state
 * in the coordinates people use, simulation settings and the output channels (docs/scenes.md).
 * ap_scene_load reads and validates it, builds the bodies with the builder (body.h) and
 * compiles the model. Every message about bad input has the form
 *
 *     FILE:LINE:COLUMN: key.path: what is wrong (and, for unknown keys, "did you mean ...?")
 *
 * and loading stops at the first one. Overrides ("bodies.disk.mass=2") replace any scalar of
 * the file by its dotted key path before it is read; sequence entries are addressed by index
 * ("bodies.disk.com.2=0.1"). */
#ifndef APPELL_SCENE_H
#define APPELL_SCENE_H

#include <stddef.h>

#include "appell/analyze.h"
#include "appell/export.h"
#include "appell/sim.h"
#include "appell/status.h"
#include "appell/system.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct ap_scene ap_scene;

/* Load a scene file, apply nsets overrides "path=value" (later ones win), validate, build and
 * compile. On failure *out is NULL, the status is AP_ERR_ARG for bad input (AP_ERR_NOMEM, ...
 * otherwise) and msg holds the one message. */
AP_API int ap_scene_load(const char *path, const char *const *sets, int nsets, ap_scene **out,
                         char *msg, size_t msg_len);
/* The same from text in memory (len bytes, need not be NUL-terminated); name stands for the
 * file name in messages. */
AP_API int ap_scene_load_string(const char *text, size_t len, const char *name,
                                const char *const *sets, int nsets, ap_scene **out, char *msg,
                                size_t msg_len);
AP_API void ap_scene_free(ap_scene *s);
/* Read a scene file as ap_scene_load reads it: at most 16 MiB (a larger file, /dev/zero, is
 * refused after reading 16 MiB + 1 bytes), not a directory. *text is a NUL-terminated copy of
 * the *len bytes, to be freed with ap_scene_text_free; on failure *text is NULL, the status
 * AP_ERR_ARG (AP_ERR_NOMEM when out of memory) and msg says "PATH: why"; errno is fopen's
 * when the file could not be opened, 0 after any other outcome. ap_scene_load_string
 * refuses text longer than 16 MiB the same way. */
AP_API int ap_scene_read(const char *path, char **text, size_t *len, char *msg, size_t msg_len);
AP_API void ap_scene_text_free(char *text);

/* The compiled model (owned by the scene). */
AP_API const ap_model *ap_scene_model(const ap_scene *s);
/* Why the scene's model runs interpreted although simulation.compile (or APPELL_COMPILE) asked
 * for compiled code (one line, docs/compiled.md), or "" (also for NULL). */
AP_API const char *ap_scene_compile_notice(const ap_scene *s);

/* Simulation settings of the scene (simulation: and output: sections). */
typedef struct ap_scene_run {
  ap_sim_def sim;          /* mode, method (points into the scene), rtol, atol, h_fixed, ... */
  double t0;               /* start time (s); default 0 */
  double t_end;            /* end time (s); default 10 */
  double interval;         /* output interval (s); default 0.01 */
} ap_scene_run;

AP_API void ap_scene_get_run(const ap_scene *s, ap_scene_run *run);

/* Add the scene's events (its events: section and the bodies' collide: keys; docs/scenes.md
 * "Events") to a simulation of its model (appell/event.h). The event functions read the
 * scene: it must outlive the simulation. AP_ERR_ARG for a NULL s or sim, or a simulation of
 * a model of other sizes; otherwise
 * ap_sim_add_event's status with msg (may be NULL) saying why. A scene without events adds
 * nothing (and the simulation then evaluates nothing of them). */
AP_API int ap_scene_add_events(const ap_scene *s, ap_sim *sim, char *msg, size_t msg_len);

/* Declare the scene's inputs (its inputs: section, docs/control.md) on a simulation of its
 * model (ap_sim_declare_inputs; appell/control.h), all 0. A scene without the section declares
 * nothing. AP_ERR_ARG for a NULL s or sim or a simulation of a model of other sizes (msg, may
 * be NULL, says which). */
AP_API int ap_scene_add_inputs(const ap_scene *s, ap_sim *sim, char *msg, size_t msg_len);

/* The initial state (n coordinates, k speeds) made consistent with the constraints: unit
 * quaternions, loop closures assembled, unspecified speeds completed and over-specified ones
 * projected (nearest in the metric g). report (may be NULL) receives a description of every
 * correction, empty when none was needed. An impossible state (no consistent speeds, a loop
 * that cannot close, a shape singular there) gives AP_ERR_ARG or the core's status and msg.
 * So does a scene that a simulation would refuse at t0: an expression (drive, ground motion,
 * prescribed speed, applied force) that is not finite at t0 with its first and second
 * derivatives (`1/t`, `log(t-1)`, `abs(t)` at t0 = 0), or equations of motion that are not
 * finite at the initial state (speeds that overflow); msg then names FILE:LINE:COLUMN.
 * AP_ERR_ARG when s, q0 or v0 is NULL; report and msg may be NULL. */
AP_API int ap_scene_initial_state(ap_scene *s, double *q0, double *v0, char *report,
                                  size_t report_len, char *msg, size_t msg_len);

/* Evaluate every expression of the scene (drives, ground motion, prescribed speeds, applied
 * forces) with its first and second time derivatives at time t. AP_OK when all are finite;
 * otherwise AP_ERR_ARG, and msg names the first in the file that is not:
 * "FILE:LINE:COLUMN: key.path: 'log(t-1)' is not finite at t = 0: log(-1) = nan (column 1 of
 * the expression)". Only reads the scene: safe from any thread. For a run that failed with
 * AP_ERR_CALLBACK or AP_ERR_NAN, call it at the failing time to locate the cause. */
AP_API int ap_scene_check_time(const ap_scene *s, double t, char *msg, size_t msg_len);
/* After a run of this scene failed mid-run (ap_sim_advance to tout returned an error, whatever
 * the method or mode): the scene expression that is not finite where it failed, if any.
 * Checks every expression of t and every expression of the state at the failing evaluation
 * (ap_sim_failed_state(sim) after a failed advance, else ap_sim_data(sim): its t, q and v,
 * when they are finite), then the expressions of t at tout
 * (a drive with a pole at tout makes the integrator give up short of it). AP_ERR_ARG and msg
 * "FILE:LINE:COLUMN: key.path: 'EXPR' is not finite at t = T: OPERATION (column C of the
 * expression)" when one is found; AP_OK and msg "" otherwise (the cause is not a scene
 * expression). AP_ERR_ARG for NULL sc or sim. */
AP_API int ap_scene_locate_failure(const ap_scene *s, const ap_sim *sim, double tout, char *msg,
                                   size_t msg_len);

/* Output channels: column names of a row (column 0 is "t") and their values at the
 * simulation's current state. Count 0 and name NULL when s is NULL or i out of range; the row
 * is AP_ERR_ARG for a NULL argument or a simulation of another model. */
AP_API int ap_scene_output_count(const ap_scene *s);
AP_API const char *ap_scene_output_name(const ap_scene *s, int i);
AP_API int ap_scene_output_row(ap_scene *s, ap_sim *sim, double *row);

/* Total mechanical energy (kinetic + potential of gravity and springs) at (t, q, v), and the
 * largest |A v + a0| there. AP_ERR_ARG when an argument is NULL. */
AP_API int ap_scene_energy(ap_scene *s, double t, const double *q, const double *v, double *E);
AP_API int ap_scene_residual(ap_scene *s, double t, const double *q, const double *v,
                             double *resid);

/* 1 when nothing in the scene adds or removes energy: no drivers, damping, applied forces,
 * prescribed non-zero speeds or moving ground; the energy drift then measures the error.
 * 0 when s is NULL. */
AP_API int ap_scene_conserves_energy(const ap_scene *s);

/* Outputs of one run, for many runs of one scene at once. ap_scene_output_row, ap_scene_energy
 * and ap_scene_residual evaluate in the scene's own data and remember the previous row (angle
 * unwrapping, E(t0)), so they serve one simulation at a time and their memory carries over to
 * the next run. An ap_scene_out keeps that state for one run: any number of them may evaluate
 * rows of one scene from different threads at once (the scene and its model are only read;
 * ap_scene_initial_state and ap_sim_create only read them too). The scene must outlive them. */
typedef struct ap_scene_out ap_scene_out;
/* (AP_ERR_ARG for a NULL argument, or a simulation of another model.) */

AP_API int ap_scene_out_create(const ap_scene *s, ap_scene_out **out);
/* The row of ap_scene_output_row (ap_scene_output_count values, column 0 = t) at the
 * simulation's current state; the first row after creation sets E(t0) and the angles. */
AP_API int ap_scene_out_row(ap_scene_out *o, ap_sim *sim, double *row);
/* ap_scene_energy in the run's own data. */
AP_API int ap_scene_out_energy(ap_scene_out *o, double t, const double *q, const double *v,
                               double *E);
AP_API void ap_scene_out_free(ap_scene_out *o);

/* The value of a constant expression of the scene grammar ("70*deg", "pi/2", "1e-3"); on
 * failure AP_ERR_ARG and msg says what is wrong with the text. */
AP_API int ap_scene_constant(const char *text, double *x, char *msg, size_t msg_len);

/* The scene's elements, for listings (appell check). */
typedef enum ap_scene_section {
  AP_SCENE_BODIES = 0,
  AP_SCENE_JOINTS = 1,
  AP_SCENE_CONSTRAINTS = 2,
  AP_SCENE_EFFECTS = 3,
  AP_SCENE_CHANNELS = 4    /* the output channels asked for (coordinates, energy, ...) */
} ap_scene_section;

/* 0, NULL, NULL when s is NULL, sec unknown or i out of range. */
AP_API int ap_scene_count(const ap_scene *s, ap_scene_section sec);
AP_API const char *ap_scene_element_name(const ap_scene *s, ap_scene_section sec, int i);
AP_API const char *ap_scene_element_kind(const ap_scene *s, ap_scene_section sec, int i);
/* The scene's parameters (its parameters: section, docs/scenes.md "Parameters"), in file
 * order: how many, and entry i's name (points into the scene) and value as evaluated at load
 * (after --set). 0 parameters when s is NULL; AP_ERR_ARG for i out of range or NULL outputs. */
AP_API int ap_scene_parameter_count(const ap_scene *s);
AP_API int ap_scene_parameter(const ap_scene *s, int i, const char **name, double *value);
/* A body's visual-only shape (bodies: NAME: visual:, docs/scenes.md): drawn by `appell view`
 * and exported by `appell export`, never seen by the dynamics. */
typedef enum ap_visual_kind {
  AP_VISUAL_NONE = 0,      /* no visual (default) */
  AP_VISUAL_BOX = 1,       /* box of edge lengths size[0..2] along body x, y, z */
  AP_VISUAL_CAPSULE = 2,   /* cylinder of `radius` and `length` along body `axis`, capped by two
                              half-spheres (total length length + 2 radius) */
  AP_VISUAL_SPHERE = 3     /* sphere of `radius` */
} ap_visual_kind;

typedef struct ap_scene_visual {
  ap_visual_kind kind;     /* default AP_VISUAL_NONE */
  double size[3];          /* box edge lengths (m); default 0 */
  double radius;           /* capsule, sphere (m); default 0 */
  double length;           /* capsule cylinder length (m); default 0 */
  int axis;                /* capsule axis in body axes: 0 x, 1 y, 2 z; default 2 */
  double at[3];            /* centre in body axes (m); default 0 */
} ap_scene_visual;

/* Body `body`'s visual (ids as ap_scene_element_name(s, AP_SCENE_BODIES, i) and the model's
 * ap_model_find_body). AP_ERR_ARG when s or out is NULL or body is out of range. */
AP_API int ap_scene_body_visual(const ap_scene *s, int body, ap_scene_visual *out);

/* The scene's name (name: key, default the file name without directory and extension); NULL
 * when s is NULL. */
AP_API const char *ap_scene_name(const ap_scene *s);

/* The scene's linearize: section (docs/linearize.md): how to find its operating point and what
 * to report. The guess of the operating point is the scene's initial state with the overrides
 * `sets` applied (reload the scene with them); the speed parameter s sets each initial rate
 * speed_keys[i] to speed_coef[i] * s. Name lists are NULL-terminated (NULL when absent). */
typedef struct ap_scene_lin {
  int present;             /* the scene has a linearize: section */
  ap_lin_about about;      /* default AP_LIN_STEADY */
  int nsets;
  char **sets;             /* "initial.<joint>.<key>=<value>" from linearize.initial */
  int nspeed;
  char **speed_keys;       /* "initial.<joint>.<key>" from linearize.speed */
  double *speed_coef;      /* their coefficients */
  char **free, **independent, **inputs, **states;
  int drop_cyclic;         /* default 1 */
  double sweep_from, sweep_to;
  int sweep_count;         /* 0: no sweep given */
} ap_scene_lin;

/* Read the linearize: section (an absent section gives present = 0 and the defaults). Its
 * inputs are the scene's inputs: section when it lists none (docs/control.md), with or
 * without the section. The result owns its arrays: ap_scene_lin_free. */
AP_API int ap_scene_get_linearize(const ap_scene *s, ap_scene_lin *out, char *msg,
                                  size_t msg_len);
AP_API void ap_scene_lin_free(ap_scene_lin *l);

/* The guess of a scene's operating point, as appell linearize makes it: the scene loaded with
 * the overrides and linearize.initial, and its initial state; with a speed parameter
 * (linearize.speed) also the speeds at speed 0 and per unit of speed (the initial state is
 * linear in the given rates). */
typedef struct ap_scene_lin_guess {
  ap_scene_lin sec;        /* the section */
  ap_scene *scene;         /* loaded with the overrides and then linearize.initial */
  int n, k;                /* its model's coordinates and speeds */
  double t0;               /* its start time */
  double *q, *v;           /* (n), (k): its initial state, the guess */
  double *v0, *dir;        /* (k) each with a speed parameter (else NULL): the speeds at
                              speed 0 and per unit of speed */
  double speed;            /* the speed of the scene's own rates (least squares of
                              v = v0 + speed dir); NaN without a speed parameter */
} ap_scene_lin_guess;

/* Load the guess from the scene file path, or (text non-NULL) from text of len bytes named
 * path in messages, with nsets overrides "path=value". The result owns its scene and arrays:
 * ap_scene_lin_guess_free (also after a failure). Errors as ap_scene_load's. */
AP_API int ap_scene_lin_guess_load(const char *path, const char *text, size_t len,
                                   const char *const *sets, int nsets, ap_scene_lin_guess *out,
                                   char *msg, size_t msg_len);
AP_API void ap_scene_lin_guess_free(ap_scene_lin_guess *g);
/* The linearizer's definition the section gives (about, free, independent, inputs, the speed
 * direction; the lists point into g); change fields before ap_scene_lin_create. */
AP_API ap_lin_def ap_scene_lin_def(const ap_scene_lin_guess *g);
/* A linearizer of the guess's model at its state with def (NULL: ap_scene_lin_def(g)); the
 * speeds are v0 when def has the speed direction, so that ap_lin_operating_point(L, s) starts
 * at v0 + s dir. As ap_lin_create: on failure *out may hold the linearizer with the message. */
AP_API int ap_scene_lin_create(const ap_scene_lin_guess *g, const ap_lin_def *def,
                               ap_lin **out);

#ifdef __cplusplus
}
#endif
#endif
