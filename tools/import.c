/* appell import: convert a URDF robot description into a scene file (docs/urdf.md).
 *
 * Reads the URDF with ap_urdf_to_scene (lib/scene/urdf.c), loads the resulting scene with
 * ap_scene_load_string to prove that it compiles and has a consistent initial state, and only
 * then writes it (--out FILE through ap_out_write_file: all or nothing; standard output
 * without --out). Exit 0 on success, 2 for bad input (the message names FILE:LINE and the
 * element), 1 for an internal error or a failed write. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "cli.h"

static const char help[] =
    "usage: appell import ROBOT.urdf [--out SCENE.yaml] [--wheels LINK,LINK...]\n"
    "                    [--wheel-shape disk|torus]\n"
    "\n"
    "Convert a URDF robot description into a scene (docs/urdf.md): links become bodies,\n"
    "joints keep their kind, origin, axis and limits, collision spheres become shapes, and\n"
    "the links named by --wheels roll on the ground (their collision cylinder becomes a disk\n"
    "or a torus of its radius). The scene is loaded before it is written.\n"
    "\n"
    "options:\n"
    "  --out FILE          the scene file to write (default: standard output)\n"
    "  --wheels A,B        links that roll on the ground (repeatable)\n"
    "  --wheel-shape S     disk (default) or torus (tube radius half the cylinder's length)\n"
    "  -h, --help          this help\n"
    "\n"
    "Exit codes: 0 written, 2 bad input (nothing written), 1 internal error or failed write.\n";

#define MAX_WHEELS 64

typedef struct import_opts {
  const char *urdf, *out;
  const char *wheels[MAX_WHEELS];
  int nwheels;
  ap_urdf_wheel_shape shape;
  char names[4096];         /* the wheel names, each NUL-terminated */
  size_t used;              /* bytes of names in use */
} import_opts;

/* Split "a,b" into o->wheels (copied into o->names). */
static int add_wheels(import_opts *o, const char *list) {
  for (const char *s = list; *s;) {
    size_t n = strcspn(s, ",");
    if (n == 0 || o->nwheels >= MAX_WHEELS || o->used + n + 1 > sizeof o->names) {
      fprintf(stderr, "appell import: --wheels '%s': %s\n", list,
              n == 0 ? "an empty link name" : "too many wheels");
      return -1;
    }
    char *dst = o->names + o->used;
    memcpy(dst, s, n);
    dst[n] = '\0';
    o->wheels[o->nwheels++] = dst;
    o->used += n + 1;
    s += n + (s[n] == ',');
  }
  return 0;
}

static int parse_args(int argc, char **argv, import_opts *o) {
  static const char *const known[] = {"--out", "--wheels", "--wheel-shape", "--help", NULL};
  for (int i = 1; i < argc; i++) {
    const char *v = NULL;
    int r;
    if (strcmp(argv[i], "-h") == 0 || strcmp(argv[i], "--help") == 0) {
      fputs(help, stdout);
      return 1;
    }
    if ((r = cli_opt(argc, argv, &i, "--out", &v)) != 0) {
      if (r < 0) return cli_need("import", "--out", "a file name");
      o->out = v;
    } else if ((r = cli_opt(argc, argv, &i, "--wheels", &v)) != 0) {
      if (r < 0 || add_wheels(o, v)) return r < 0 ? cli_need("import", "--wheels", NULL) : -1;
    } else if ((r = cli_opt(argc, argv, &i, "--wheel-shape", &v)) != 0) {
      if (r < 0) return cli_need("import", "--wheel-shape", "disk or torus");
      if (strcmp(v, "disk") && strcmp(v, "torus")) {
        fprintf(stderr, "appell import: --wheel-shape: '%s' is not disk or torus\n", v);
        return -1;
      }
      o->shape = strcmp(v, "torus") == 0 ? AP_URDF_WHEEL_TORUS : AP_URDF_WHEEL_DISK;
    } else if (argv[i][0] == '-' && argv[i][1] != '\0') {
      cli_unknown("import", argv[i], known);
      return -1;
    } else if (!o->urdf) {
      o->urdf = argv[i];
    } else {
      fprintf(stderr, "appell import: one URDF file only (got '%s' and '%s')\n", o->urdf,
              argv[i]);
      return -1;
    }
  }
  if (!o->urdf) {
    fputs("appell import: no URDF file given (see appell import --help)\n", stderr);
    return -1;
  }
  return 0;
}

/* The scene must load: compiled model and a consistent initial state. */
static int check_scene(const import_opts *o, const char *yaml, size_t len) {
  char name[1200], msg[2048];
  snprintf(name, sizeof name, "%s (imported scene)", o->urdf);
  ap_scene *sc = NULL;
  int rc = ap_scene_load_string(yaml, len, name, NULL, 0, &sc, msg, sizeof msg);
  if (rc == AP_OK) {
    const ap_model *m = ap_scene_model(sc);
    int n = ap_model_n(m), k = ap_model_k(m);
    double *q = calloc((size_t)n + 1, sizeof *q), *v = calloc((size_t)k + 1, sizeof *v);
    rc = q && v ? ap_scene_initial_state(sc, q, v, NULL, 0, msg, sizeof msg) : AP_ERR_NOMEM;
    free(q);
    free(v);
  }
  ap_scene_free(sc);
  if (rc != AP_OK) fprintf(stderr, "appell import: %s\n", msg[0] ? msg : ap_strerror(rc));
  return rc;
}

int cmd_import(int argc, char **argv) {
  import_opts o;
  memset(&o, 0, sizeof o);
  int r = parse_args(argc, argv, &o);
  if (r != 0) return r > 0 ? EXIT_OK : EXIT_INPUT;
  ap_urdf_def def = ap_urdf_def_default();
  def.wheels = o.wheels;
  def.nwheels = o.nwheels;
  def.wheel_shape = o.shape;
  char *yaml = NULL, msg[2048];
  size_t len = 0;
  int rc = ap_urdf_to_scene(o.urdf, &def, &yaml, &len, msg, sizeof msg);
  if (rc != AP_OK) {
    fprintf(stderr, "appell import: %s\n", msg);
    return cli_exit_code(rc);
  }
  rc = check_scene(&o, yaml, len);
  if (rc == AP_OK && (!o.out || strcmp(o.out, "-") == 0)) {
    fwrite(yaml, 1, len, stdout);
  } else if (rc == AP_OK) {
    const char *keep[1] = {o.urdf};
    rc = ap_out_write_file(o.out, yaml, len, keep, 1, NULL, msg, sizeof msg);
    if (rc != AP_OK) fprintf(stderr, "appell import: %s\n", msg);
  }
  ap_scene_text_free(yaml);
  return cli_exit_code(rc);
}
