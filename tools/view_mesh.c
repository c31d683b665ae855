/* appell export: triangle meshes of the bodies' shapes in body axes, for the glTF file.
 *
 * Each body's mesh is the union of parts with a colour per vertex (glTF COLOR_0):
 *   disk        a cylinder of the disk's radius, 4 % of it thick, axis body z, and one red spoke
 *   torus       the tube swept around the body z axis, and one red spoke
 *   sphere,     a UV sphere (scaled to the semi-axes), the meridian sector in the body xz plane
 *   ellipsoid   (longitude 0) coloured red so that rotation shows
 *   visual      box, capsule (cylinder and two spheres) or sphere at `at`
 *   no shape    a triad: three thin boxes along body x (red), y (green), z (blue)
 * Normals are unit vectors; indices are 16-bit (every part stays far below 65536 vertices). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "view.h"

static const double pi = 3.14159265358979323846;

typedef struct mesh_b {
  view_mesh *m;
  int cap_v, cap_i, fail;
  float color[3];
} mesh_b;

static int vertex(mesh_b *b, const double p[3], const double n[3]) {
  view_mesh *m = b->m;
  if (m->nv == b->cap_v) {
    int nc = b->cap_v ? 2 * b->cap_v : 256;
    float *pp = realloc(m->pos, sizeof *pp * 3 * (size_t)nc);
    if (pp) m->pos = pp;
    float *nn = realloc(m->normal, sizeof *nn * 3 * (size_t)nc);
    if (nn) m->normal = nn;
    float *cc = realloc(m->color, sizeof *cc * 3 * (size_t)nc);
    if (cc) m->color = cc;
    if (!pp || !nn || !cc) return b->fail = 1, 0;
    b->cap_v = nc;
  }
  double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (int i = 0; i < 3; i++) {
    m->pos[3 * m->nv + i] = (float)p[i];
    m->normal[3 * m->nv + i] = (float)(len > 0 ? n[i] / len : i == 2);
    m->color[3 * m->nv + i] = b->color[i];
  }
  return m->nv++;
}

static void tri(mesh_b *b, int i0, int i1, int i2) {
  view_mesh *m = b->m;
  if (b->fail) return;
  if (m->ni + 3 > b->cap_i) {
    int nc = b->cap_i ? 2 * b->cap_i : 768;
    unsigned short *ii = realloc(m->index, sizeof *ii * (size_t)nc);
    if (!ii) {
      b->fail = 1;
      return;
    }
    m->index = ii, b->cap_i = nc;
  }
  m->index[m->ni++] = (unsigned short)i0;
  m->index[m->ni++] = (unsigned short)i1;
  m->index[m->ni++] = (unsigned short)i2;
}

/* Point of a local frame: centre c, axes permuted so that local z is body axis `axis`. */
static void place(const double c[3], int axis, const double l[3], double out[3]) {
  int ax[3] = {(axis + 1) % 3, (axis + 2) % 3, axis};
  for (int i = 0; i < 3; i++) out[ax[i]] = l[i];
  for (int i = 0; c && i < 3; i++) out[i] += c[i];
}

/* A box of edge lengths s centred at c (flat-shaded faces). */
static void box(mesh_b *b, const double c[3], const double s[3]) {
  for (int f = 0; f < 6; f++) {
    int ax = f % 3;
    double sign = f < 3 ? 1.0 : -1.0, n[3] = {0, 0, 0};
    n[ax] = sign;
    int u = (ax + 1) % 3, v = (ax + 2) % 3, first = b->m->nv;
    for (int k = 0; k < 4; k++) {
      double p[3];
      p[ax] = c[ax] + sign * s[ax] / 2;
      p[u] = c[u] + ((k == 1 || k == 2) ? 0.5 : -0.5) * s[u];
      p[v] = c[v] + (k >= 2 ? 0.5 : -0.5) * s[v] * sign;
      vertex(b, p, n);
    }
    tri(b, first, first + 1, first + 2);
    tri(b, first, first + 2, first + 3);
  }
}

/* Ellipsoid with semi-axes a centred at c; the sector of longitude 0 (about z) painted red
 * when `mark`. */
static void ellipsoid(mesh_b *b, const double c[3], const double a[3], int mark) {
  enum { NU = 36, NV = 18 };
  float keep[3];
  memcpy(keep, b->color, sizeof keep);
  for (int j = 0; j <= NV; j++) {
    double th = pi * j / NV;
    for (int i = 0; i <= NU; i++) {
      double ph = 2 * pi * i / NU, u[3] = {sin(th) * cos(ph), sin(th) * sin(ph), cos(th)};
      double p[3], n[3];
      for (int k = 0; k < 3; k++) p[k] = c[k] + a[k] * u[k], n[k] = u[k] / a[k];
      int red = mark && (i == 0 || i == NU);
      if (red) b->color[0] = 0.9f, b->color[1] = 0.15f, b->color[2] = 0.1f;
      vertex(b, p, n);
      memcpy(b->color, keep, sizeof keep);
    }
  }
  int base = b->m->nv - (NU + 1) * (NV + 1);
  for (int j = 0; j < NV; j++)
    for (int i = 0; i < NU; i++) {
      int p0 = base + j * (NU + 1) + i, p1 = p0 + NU + 1;
      tri(b, p0, p1, p0 + 1);
      tri(b, p0 + 1, p1, p1 + 1);
    }
}

/* Closed cylinder of radius r and length h along body axis `axis`, centred at c. */
static void cylinder(mesh_b *b, const double c[3], int axis, double r, double h) {
  enum { NS = 48 };
  for (int side = 0; side < 2; side++) {
    int base = b->m->nv;
    for (int i = 0; i <= NS; i++) {
      double ph = 2 * pi * i / NS, l[3] = {r * cos(ph), r * sin(ph), -h / 2}, p[3], n[3];
      double ln[3] = {cos(ph), sin(ph), 0};
      for (int e = 0; e < 2; e++) {
        l[2] = (e ? 1 : -1) * h / 2;
        place(c, axis, l, p);
        place(NULL, axis, ln, n);
        vertex(b, p, n);
      }
    }
    for (int i = 0; side == 0 && i < NS; i++) {
      int q = base + 2 * i;
      tri(b, q, q + 2, q + 1);
      tri(b, q + 1, q + 2, q + 3);
    }
    if (side == 0) continue;
    for (int e = 0; e < 2; e++) {   /* the two caps */
      double sgn = e ? 1 : -1, lc[3] = {0, 0, sgn * h / 2}, ln[3] = {0, 0, sgn}, p[3], n[3];
      place(c, axis, lc, p);
      place(NULL, axis, ln, n);
      int mid = vertex(b, p, n), ring = b->m->nv;
      for (int i = 0; i <= NS; i++) {
        double ph = 2 * pi * i / NS, l[3] = {r * cos(ph), r * sin(ph), sgn * h / 2};
        place(c, axis, l, p);
        vertex(b, p, n);
      }
      for (int i = 0; i < NS; i++)
        if (e) tri(b, mid, ring + i, ring + i + 1);
        else tri(b, mid, ring + i + 1, ring + i);
    }
  }
}

static void torus(mesh_b *b, double R, double a) {
  enum { NU = 48, NV = 16 };
  int base = b->m->nv;
  for (int i = 0; i <= NU; i++)
    for (int j = 0; j <= NV; j++) {
      double ph = 2 * pi * i / NU, th = 2 * pi * j / NV;
      double n[3] = {cos(th) * cos(ph), cos(th) * sin(ph), sin(th)};
      double p[3] = {R * cos(ph) + a * n[0], R * sin(ph) + a * n[1], a * n[2]};
      vertex(b, p, n);
    }
  for (int i = 0; i < NU; i++)
    for (int j = 0; j < NV; j++) {
      int p0 = base + i * (NV + 1) + j, p1 = p0 + NV + 1;
      tri(b, p0, p1, p0 + 1);
      tri(b, p0 + 1, p1, p1 + 1);
    }
}

static void set_color(mesh_b *b, float r, float g, float bl) {
  b->color[0] = r, b->color[1] = g, b->color[2] = bl;
}

static void wheel_spoke(mesh_b *b, double r, double w) {
  double c[3] = {0, 0, 0}, s[3] = {1.9 * r, 0.08 * r, w};
  set_color(b, 0.9f, 0.15f, 0.1f);
  box(b, c, s);
}

static void shape(mesh_b *b, const ap_shape *s) {
  double o[3] = {0, 0, 0};
  set_color(b, 0.25f, 0.45f, 0.75f);
  if (s->kind == AP_SHAPE_DISK) {
    double w = fmax(0.04 * s->radius, 0.004);
    cylinder(b, o, 2, s->radius, w);
    wheel_spoke(b, s->radius, 1.5 * w);
  } else if (s->kind == AP_SHAPE_TORUS) {
    torus(b, s->radius, s->tube);
    wheel_spoke(b, s->radius, s->tube);
  } else if (s->kind == AP_SHAPE_SPHERE) {
    double a[3] = {s->radius, s->radius, s->radius};
    ellipsoid(b, o, a, 1);
  } else if (s->kind == AP_SHAPE_ELLIPSOID) {
    ellipsoid(b, o, s->semi_axes, 1);
  }
}

static void visual(mesh_b *b, const ap_scene_visual *v) {
  set_color(b, 0.8f, 0.6f, 0.3f);
  if (v->kind == AP_VISUAL_BOX) box(b, v->at, v->size);
  if (v->kind == AP_VISUAL_SPHERE) {
    double a[3] = {v->radius, v->radius, v->radius};
    ellipsoid(b, v->at, a, 0);
  }
  if (v->kind != AP_VISUAL_CAPSULE) return;
  cylinder(b, v->at, v->axis, v->radius, v->length);
  for (int e = 0; e < 2; e++) {
    double l[3] = {0, 0, (e ? 0.5 : -0.5) * v->length}, c[3], a[3] = {v->radius, v->radius,
                                                                     v->radius};
    place(v->at, v->axis, l, c);
    ellipsoid(b, c, a, 0);
  }
}

static void triad(mesh_b *b, double len) {
  for (int ax = 0; ax < 3; ax++) {
    double c[3] = {0, 0, 0}, s[3] = {0.06 * len, 0.06 * len, 0.06 * len};
    c[ax] = len / 2, s[ax] = len;
    set_color(b, ax == 0, ax == 1, ax == 2);
    box(b, c, s);
  }
}

int view_mesh_body(const view_body *vb, view_mesh *m) {
  memset(m, 0, sizeof *m);
  mesh_b b = {m, 0, 0, 0, {0, 0, 0}};
  shape(&b, &vb->shape);
  visual(&b, &vb->visual);
  if (vb->shape.kind == AP_SHAPE_NONE || vb->shape.kind == AP_SHAPE_POINT) triad(&b, 0.1);
  if (b.fail) view_mesh_free(m);
  return b.fail ? -1 : 0;
}

void view_mesh_free(view_mesh *m) {
  free(m->pos);
  free(m->normal);
  free(m->color);
  free(m->index);
  memset(m, 0, sizeof *m);
}
