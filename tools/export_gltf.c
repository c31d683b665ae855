/* appell export: a run as a glTF 2.0 binary (.glb), docs/viewer.md "Export".
 *
 *   appell export SCENE --run FILE.csv --format gltf --out FILE.glb
 *
 * One node per body at the scene's root (so a node's transform is the body's world pose), one
 * mesh per body (tools/view_mesh.c, vertex colours), a static node and mesh per ground
 * surface (the plane about the motion or the ground sphere, world axes: view_ground.c), one animation with a translation and a
 * rotation channel per body sampled at the CSV's rows (LINEAR; quaternions x y z w as glTF
 * wants them), time = t - t0. All numbers are float32, as glTF stores them: the samples equal
 * the poses rebuilt from the CSV (view_frames.c) to float precision. A row whose float32 time
 * does not exceed the previous kept row's is dropped (glTF needs strictly increasing times).
 *
 * GLB layout: the 12-byte header, the JSON chunk (padded with spaces), the BIN chunk (padded
 * with zeros); one buffer view per accessor, each 4-byte aligned. */
#include <errno.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "view.h"

typedef struct glb {
  unsigned char *bin;
  size_t len, cap;
  FILE *js;                /* the JSON's accessors, written as they are added */
  FILE *views;             /* the JSON's buffer views */
  int nacc;
  int fail;
} glb;

static size_t add_bytes(glb *g, const void *p, size_t n) {
  size_t need = g->len + n + 4;
  if (need > g->cap) {
    size_t nc = g->cap ? g->cap : 1 << 16;
    while (nc < need) nc *= 2;
    unsigned char *b = realloc(g->bin, nc);
    if (!b) return g->fail = 1, 0;
    g->bin = b, g->cap = nc;
  }
  size_t at = g->len;
  memcpy(g->bin + at, p, n);
  g->len += n;
  while (g->len % 4) g->bin[g->len++] = 0;
  return at;
}

/* An accessor over n elements of `type` (comp floats or u16) with its own buffer view. */
static int accessor(glb *g, const void *p, int n, const char *type, int ncomp, int is_index,
                    int target, const float *mn, const float *mx) {
  size_t bytes = (size_t)n * (size_t)ncomp * (is_index ? 2 : 4);
  size_t at = add_bytes(g, p, bytes);
  fprintf(g->views, "%s{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu", g->nacc ? "," : "",
          at, bytes);
  if (target) fprintf(g->views, ",\"target\":%d", target);
  fputc('}', g->views);
  fprintf(g->js, "%s{\"bufferView\":%d,\"componentType\":%d,\"count\":%d,\"type\":\"%s\"",
          g->nacc ? "," : "", g->nacc, is_index ? 5123 : 5126, n, type);
  for (int k = 0; mn && k < 2; k++) {
    const float *v = k ? mx : mn;
    fprintf(g->js, ",\"%s\":[", k ? "max" : "min");
    for (int i = 0; i < ncomp; i++) fprintf(g->js, i ? ",%.9g" : "%.9g", (double)v[i]);
    fputc(']', g->js);
  }
  fputc('}', g->js);
  return g->nacc++;
}

static void bounds(const float *x, int n, int ncomp, float *mn, float *mx) {
  for (int c = 0; c < ncomp; c++) mn[c] = mx[c] = n ? x[c] : 0.0f;
  for (int i = 0; i < n; i++)
    for (int c = 0; c < ncomp; c++) {
      float v = x[(size_t)i * (size_t)ncomp + (size_t)c];
      if (v < mn[c]) mn[c] = v;
      if (v > mx[c]) mx[c] = v;
    }
}

/* Mesh m named name: its four accessors; writes the mesh's JSON to meshes (after the first
 * when b > 0). */
static void put_mesh(glb *g, const view_mesh *m_, const char *name, FILE *meshes, int b) {
  const view_mesh m = *m_;
  float mn[3], mx[3];
  bounds(m.pos, m.nv, 3, mn, mx);
  int ap = accessor(g, m.pos, m.nv, "VEC3", 3, 0, 34962, mn, mx);
  int an = accessor(g, m.normal, m.nv, "VEC3", 3, 0, 34962, NULL, NULL);
  int ac = accessor(g, m.color, m.nv, "VEC3", 3, 0, 34962, NULL, NULL);
  int ai = accessor(g, m.index, m.ni, "SCALAR", 1, 1, 34963, NULL, NULL);
  fprintf(meshes, "%s{\"name\":\"%s\",\"primitives\":[{\"attributes\":{\"POSITION\":%d,"
          "\"NORMAL\":%d,\"COLOR_0\":%d},\"indices\":%d,\"material\":0}]}", b ? "," : "",
          name, ap, an, ac, ai);
}

/* Mesh of body b (its shape, visual or triad), then of ground b - nb (view_ground.c). */
static int body_mesh(glb *g, const view_frames *f, FILE *meshes, int b) {
  view_mesh m;
  char name[32];
  snprintf(name, sizeof name, "ground%.0d", b - f->nb);
  if ((b < f->nb ? view_mesh_body(&f->bodies[b], &m) : view_mesh_ground(f, &f->ground[b - f->nb],
                                                                       &m)) != 0)
    return -1;
  put_mesh(g, &m, b < f->nb ? f->bodies[b].name : name, meshes, b);
  view_mesh_free(&m);
  return 0;
}

/* Rows kept: float32 times strictly increasing from 0. */
static int keep_rows(const view_frames *f, long *rows, float *times) {
  int nt = 0;
  for (long r = 0; r < f->nf; r++) {
    float t = (float)(f->t[r] - f->t[0]);
    if (nt && !(t > times[nt - 1])) continue;
    rows[nt] = r, times[nt++] = t;
  }
  return nt;
}

static void animation(glb *g, const view_frames *f, FILE *anim) {
  long *rows = malloc(sizeof *rows * (size_t)f->nf);
  float *times = malloc(sizeof *times * (size_t)f->nf);
  float *buf = malloc(sizeof *buf * 4 * (size_t)f->nf);
  if (!rows || !times || !buf) {
    g->fail = 1;
    free(rows), free(times), free(buf);
    return;
  }
  int nt = keep_rows(f, rows, times);
  float mn, mx;
  bounds(times, nt, 1, &mn, &mx);
  int at = accessor(g, times, nt, "SCALAR", 1, 0, 0, &mn, &mx);
  fputs("\"animations\":[{\"name\":\"run\",\"samplers\":[", anim);
  for (int b = 0; b < f->nb; b++)
    for (int k = 0; k < 2; k++) {
      for (int i = 0; i < nt; i++) {
        const double *p = f->pose + ((size_t)rows[i] * (size_t)f->nb + (size_t)b) * 7;
        if (k == 0)
          for (int c = 0; c < 3; c++) buf[3 * i + c] = (float)p[c];
        else
          buf[4 * i] = (float)p[4], buf[4 * i + 1] = (float)p[5], buf[4 * i + 2] = (float)p[6],
          buf[4 * i + 3] = (float)p[3];
      }
      int a = accessor(g, buf, nt, k ? "VEC4" : "VEC3", k ? 4 : 3, 0, 0, NULL, NULL);
      fprintf(anim, "%s{\"input\":%d,\"output\":%d,\"interpolation\":\"LINEAR\"}",
              b || k ? "," : "", at, a);
    }
  fputs("],\"channels\":[", anim);
  for (int b = 0; b < f->nb; b++)
    for (int k = 0; k < 2; k++)
      fprintf(anim, "%s{\"sampler\":%d,\"target\":{\"node\":%d,\"path\":\"%s\"}}",
              b || k ? "," : "", 2 * b + k, b, k ? "rotation" : "translation");
  fputs("]}]", anim);
  free(rows), free(times), free(buf);
}

static void nodes_json(FILE *js, const view_frames *f) {
  fputs("\"scene\":0,\"scenes\":[{\"name\":\"appell\",\"nodes\":[", js);
  for (int b = 0; b < f->nb + f->ng; b++) fprintf(js, b ? ",%d" : "%d", b);
  fputs("]}],\"nodes\":[", js);
  for (int b = 0; b < f->nb; b++) {
    const double *p = f->pose + (size_t)b * 7;
    fprintf(js, "%s{\"name\":\"%s\",\"mesh\":%d,\"translation\":[%.9g,%.9g,%.9g],"
            "\"rotation\":[%.9g,%.9g,%.9g,%.9g]}", b ? "," : "", f->bodies[b].name, b,
            (double)(float)p[0], (double)(float)p[1], (double)(float)p[2], (double)(float)p[4],
            (double)(float)p[5], (double)(float)p[6], (double)(float)p[3]);
  }
  for (int k = 0; k < f->ng; k++)   /* the grounds: static, in world axes */
    fprintf(js, ",{\"name\":\"ground%.0d\",\"mesh\":%d}", k, f->nb + k);
  fputs("],", js);
}

static void put32(FILE *out, uint32_t v) {
  unsigned char b[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16),
                        (unsigned char)(v >> 24)};
  fwrite(b, 1, 4, out);
}

static int write_glb(FILE *out, const char *json, size_t jlen, const glb *g) {
  size_t jpad = (4 - jlen % 4) % 4;
  put32(out, 0x46546C67u);
  put32(out, 2);
  put32(out, (uint32_t)(12 + 8 + jlen + jpad + 8 + g->len));
  put32(out, (uint32_t)(jlen + jpad));
  put32(out, 0x4E4F534Au);
  fwrite(json, 1, jlen, out);
  for (size_t i = 0; i < jpad; i++) fputc(' ', out);
  put32(out, (uint32_t)g->len);
  put32(out, 0x004E4942u);
  fwrite(g->bin, 1, g->len, out);
  return ferror(out) ? -1 : 0;
}

/* The whole GLB of frames f into out; 0, or -1 (out of memory or a failed write). */
int view_write_gltf(FILE *out, const view_frames *f) {
  glb g = {0};
  char *acc = NULL, *views = NULL, *meshes = NULL, *anim = NULL, *json = NULL;
  size_t la = 0, lv = 0, lm = 0, ln = 0, lj = 0;
  g.js = open_memstream(&acc, &la);
  g.views = open_memstream(&views, &lv);
  FILE *fm = open_memstream(&meshes, &lm), *fa = open_memstream(&anim, &ln);
  int rc = g.js && g.views && fm && fa ? 0 : -1;
  for (int b = 0; rc == 0 && b < f->nb + f->ng; b++) rc = body_mesh(&g, f, fm, b);
  if (rc == 0) animation(&g, f, fa);
  if (g.js) fclose(g.js);
  if (g.views) fclose(g.views);
  if (fm) fclose(fm);
  if (fa) fclose(fa);
  FILE *js = rc == 0 && !g.fail ? open_memstream(&json, &lj) : NULL;
  if (js) {
    fputs("{\"asset\":{\"version\":\"2.0\",\"generator\":\"appell export\"},", js);
    nodes_json(js, f);
    fprintf(js, "\"meshes\":[%s],\"materials\":[{\"name\":\"body\",\"doubleSided\":true,"
            "\"pbrMetallicRoughness\":{\"baseColorFactor\":[1,1,1,1],\"metallicFactor\":0,"
            "\"roughnessFactor\":0.8}}],%s,\"accessors\":[%s],\"bufferViews\":[%s],"
            "\"buffers\":[{\"byteLength\":%zu}]}", meshes, anim, acc, views, g.len);
    fclose(js);
    rc = write_glb(out, json, lj, &g);
  } else {
    rc = -1;
  }
  free(acc), free(views), free(meshes), free(anim), free(json), free(g.bin);
  return rc;
}

static const char usage[] =
    "usage: appell export SCENE --run FILE.csv --format gltf --out FILE.glb [--set PATH=VALUE]\n"
    "\n"
    "Write a run as a glTF 2.0 binary: one node and mesh per body (its shape, or its visual,\n"
    "or a triad), and one animation with each body's translation and rotation at every CSV row\n"
    "(time t - t0). The CSV must hold the coordinates channel. Blender, three.js's GLTFLoader\n"
    "and any glTF viewer play it.\n";

int cmd_export(int argc, char **argv) {
  const char *scene = NULL, *run = NULL, *out = NULL, *format = "gltf", *sets[64];
  int nsets = 0;
  static const char *const known[] = {"--run", "--out", "--format", "--set", "--help", NULL};
  for (int i = 1; i < argc; i++) {
    const char *v = NULL;
    int r = 0;
    if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0)
      return fputs(usage, stdout), EXIT_OK;
    const char *const names[] = {"--run", "--out", "--format", "--set"};
    for (int k = 0; k < 4 && r == 0; k++) {
      if ((r = cli_opt(argc, argv, &i, names[k], &v)) < 0)
        return cli_need("export", names[k], NULL), EXIT_INPUT;
      if (r > 0 && k == 0) run = v;
      if (r > 0 && k == 1) out = v;
      if (r > 0 && k == 2) format = v;
      if (r > 0 && k == 3 && nsets < 64) sets[nsets++] = v;
    }
    if (r) continue;
    if (argv[i][0] == '-' && argv[i][1]) return cli_unknown("export", argv[i], known);
    scene = argv[i];
  }
  if (!scene || !run || !out) {
    fprintf(stderr, "appell export: needs SCENE, --run and --out\n%s", usage);
    return EXIT_INPUT;
  }
  if (strcmp(format, "gltf") != 0) {
    fprintf(stderr, "appell export: --format %s: the only format is gltf\n", format);
    return EXIT_INPUT;
  }
  char msg[1024] = "";
  ap_scene *sc = NULL;
  int st = ap_scene_load(scene, sets, nsets, &sc, msg, sizeof msg);
  if (st != AP_OK) return fprintf(stderr, "appell export: %s\n", msg), cli_exit_code(st);
  view_csv csv = {0};
  view_frames f = {0};
  int rc = view_csv_read("export", run, &csv);
  if (rc == EXIT_OK) rc = view_frames_build("export", sc, &csv, &f);
  cli_out o;
  cli_out_command("export");
  if (rc == EXIT_OK) rc = cli_out_check(&o, out, scene);
  if (rc == EXIT_OK) rc = cli_out_open(&o);
  if (rc == EXIT_OK) {
    if (view_write_gltf(o.f, &f) != 0 && !o.err) o.err = ENOMEM;
    rc = cli_out_close(&o, EXIT_OK);
  }
  view_frames_free(&f);
  view_csv_free(&csv);
  ap_scene_free(sc);
  return rc;
}
