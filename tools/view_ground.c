/* appell view and appell export: the ground surfaces a scene rolls on (docs/viewer.md).
 *
 * The grounds are those of the rolling and knife-edge constraints as the model compiled them
 * (ap_model_constraint_ground): planes normal . p = offset (z = 0, a tilted plane) and fixed
 * spheres (a dome, or a bowl rolled on from inside); equal ones are drawn once, at most
 * VIEW_MAX_GROUNDS, and a scene without such constraints gets the plane z = 0. The page
 * draws them from their JSON (tools/viewer/viewer.js); the glTF export gets a mesh each: a
 * square of the plane about the motion (its bounding box projected onto the plane, with a
 * margin) or a UV sphere, in world axes. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "view.h"

static int same(const view_ground *a, const view_ground *b) {
  if (a->field || b->field)
    return a->field == b->field && a->height_fn == b->height_fn &&
           a->height_user == b->height_user;
  if (a->sphere != b->sphere) return 0;
  if (a->sphere)
    return a->radius == b->radius && a->inside == b->inside &&
           !memcmp(a->center, b->center, sizeof a->center);
  return a->offset == b->offset && !memcmp(a->normal, b->normal, sizeof a->normal);
}

void view_grounds(const ap_scene *sc, view_frames *f) {
  const ap_model *m = ap_scene_model(sc);
  int nc = ap_scene_count(sc, AP_SCENE_CONSTRAINTS);
  f->ng = 0;
  for (int c = 0; c < nc && f->ng < VIEW_MAX_GROUNDS; c++) {
    ap_ground_motion gm;
    if (ap_model_constraint_ground(m, c, &gm) != AP_OK) continue;
    view_ground g = {gm.sphere_radius > 0, {0, 0, 0}, 0, {0, 0, 0}, 0, gm.inside,
                     gm.height_fn != NULL, gm.height_fn, gm.height_user};
    if (g.sphere) {
      memcpy(g.center, gm.sphere_center, sizeof g.center);
      g.radius = gm.sphere_radius;
    } else {
      memcpy(g.normal, gm.normal, sizeof g.normal);
      g.offset = gm.offset;
    }
    int seen = 0;
    for (int k = 0; k < f->ng && !seen; k++) seen = same(&f->ground[k], &g);
    if (!seen) f->ground[f->ng++] = g;
  }
  if (f->ng == 0) {
    view_ground z = {0, {0, 0, 1}, 0, {0, 0, 0}, 0, 0, 0, NULL, NULL};
    f->ground[f->ng++] = z;
  }
}

void view_grounds_json(FILE *out, const view_frames *f) {
  fputc('[', out);
  for (int k = 0; k < f->ng; k++) {
    const view_ground *g = &f->ground[k];
    if (g->field) {
      if (k) fputc(',', out);
      view_field_json(out, f, g);
    } else if (g->sphere)
      fprintf(out, "%s{\"kind\":\"sphere\",\"center\":[%.17g,%.17g,%.17g],\"radius\":%.17g,"
              "\"inside\":%d}", k ? "," : "", g->center[0], g->center[1], g->center[2],
              g->radius, g->inside);
    else
      fprintf(out, "%s{\"kind\":\"plane\",\"normal\":[%.17g,%.17g,%.17g],\"offset\":%.17g}",
              k ? "," : "", g->normal[0], g->normal[1], g->normal[2], g->offset);
  }
  fputc(']', out);
}

int view_alloc_mesh(view_mesh *m, int nv, int ni) {
  memset(m, 0, sizeof *m);
  m->pos = malloc(sizeof *m->pos * 3 * (size_t)nv);
  m->normal = malloc(sizeof *m->normal * 3 * (size_t)nv);
  m->color = malloc(sizeof *m->color * 3 * (size_t)nv);
  m->index = malloc(sizeof *m->index * (size_t)ni);
  if (!m->pos || !m->normal || !m->color || !m->index) return view_mesh_free(m), -1;
  m->nv = nv, m->ni = ni;
  for (int i = 0; i < nv; i++)
    m->color[3 * i] = 0.85f, m->color[3 * i + 1] = 0.84f, m->color[3 * i + 2] = 0.8f;
  return 0;
}

static void put_vertex(view_mesh *m, int i, const double p[3], const double n[3]) {
  for (int k = 0; k < 3; k++) m->pos[3 * i + k] = (float)p[k], m->normal[3 * i + k] = (float)n[k];
}

/* Unit tangents t1, t2 of the plane with t1 x t2 = n. */
static void tangents(const double n[3], double t1[3], double t2[3]) {
  double a[3] = {fabs(n[0]) < 0.9 ? 1.0 : 0.0, fabs(n[0]) < 0.9 ? 0.0 : 1.0, 0};
  double d = a[0] * n[0] + a[1] * n[1] + a[2] * n[2], len = 0;
  for (int k = 0; k < 3; k++) t1[k] = a[k] - d * n[k], len += t1[k] * t1[k];
  for (int k = 0; k < 3; k++) t1[k] /= sqrt(len);
  t2[0] = n[1] * t1[2] - n[2] * t1[1];
  t2[1] = n[2] * t1[0] - n[0] * t1[2];
  t2[2] = n[0] * t1[1] - n[1] * t1[0];
}

static int plane_mesh(const view_frames *f, const view_ground *g, view_mesh *m) {
  double t1[3], t2[3], lo[2] = {0, 0}, hi[2] = {0, 0};
  tangents(g->normal, t1, t2);
  for (size_t i = 0; i < (size_t)f->nf * (size_t)f->nb; i++) {
    const double *p = f->pose + 7 * i;
    double u = p[0] * t1[0] + p[1] * t1[1] + p[2] * t1[2];
    double w = p[0] * t2[0] + p[1] * t2[1] + p[2] * t2[2];
    lo[0] = fmin(lo[0], u), hi[0] = fmax(hi[0], u), lo[1] = fmin(lo[1], w), hi[1] = fmax(hi[1], w);
  }
  double margin = fmax(1.0, 0.5 * fmax(hi[0] - lo[0], hi[1] - lo[1]));
  if (view_alloc_mesh(m, 4, 6) != 0) return -1;
  for (int c = 0; c < 4; c++) {
    double u = c & 1 ? hi[0] + margin : lo[0] - margin, w = c & 2 ? hi[1] + margin : lo[1] - margin;
    double p[3];
    for (int k = 0; k < 3; k++) p[k] = g->offset * g->normal[k] + u * t1[k] + w * t2[k];
    put_vertex(m, c, p, g->normal);
  }
  static const unsigned short idx[6] = {0, 1, 3, 0, 3, 2};
  memcpy(m->index, idx, sizeof idx);
  return 0;
}

static int sphere_mesh(const view_ground *g, view_mesh *m) {
  enum { NU = 48, NV = 24 };
  const double pi = 3.14159265358979323846;
  if (view_alloc_mesh(m, (NU + 1) * (NV + 1), 6 * NU * NV) != 0) return -1;
  for (int j = 0; j <= NV; j++)
    for (int i = 0; i <= NU; i++) {
      double th = pi * j / NV, ph = 2 * pi * i / NU;
      double n[3] = {sin(th) * cos(ph), sin(th) * sin(ph), cos(th)}, p[3];
      for (int k = 0; k < 3; k++) p[k] = g->center[k] + g->radius * n[k];
      for (int k = 0; g->inside && k < 3; k++) n[k] = -n[k];
      put_vertex(m, j * (NU + 1) + i, p, n);
    }
  int t = 0;
  for (int j = 0; j < NV; j++)
    for (int i = 0; i < NU; i++) {
      unsigned short a = (unsigned short)(j * (NU + 1) + i), b = (unsigned short)(a + NU + 1);
      unsigned short q[6] = {a, b, (unsigned short)(a + 1), (unsigned short)(a + 1), b,
                             (unsigned short)(b + 1)};
      memcpy(m->index + t, q, sizeof q);
      t += 6;
    }
  return 0;
}

int view_mesh_ground(const view_frames *f, const view_ground *g, view_mesh *m) {
  if (g->field) return view_field_mesh(f, g, m);
  return g->sphere ? sphere_mesh(g, m) : plane_mesh(f, g, m);
}
