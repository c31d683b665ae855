/* appell view and appell export: a height-field ground z = h(x, y) drawn as a mesh
 * (docs/viewer.md). The model's own height function (ap_model_constraint_ground) is sampled on
 * a square grid over the motion's bounding box in (x, y) with a margin, at most VIEW_FIELD_N
 * points a side; the page gets the samples as JSON (tools/viewer/viewer.js builds the mesh),
 * the glTF export a mesh with the exact normals (-h_x, -h_y, 1) / |.|. Points where h is not
 * defined (outside a bowl's rim) are left out with the triangles that use them. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "view.h"

view_grid view_field_grid(const view_frames *f) {
  double lo[2] = {0, 0}, hi[2] = {0, 0};
  for (size_t i = 0; i < (size_t)f->nf * (size_t)f->nb; i++)
    for (int k = 0; k < 2; k++) {
      double p = f->pose[7 * i + k];
      if (i == 0 || p < lo[k]) lo[k] = p;
      if (i == 0 || p > hi[k]) hi[k] = p;
    }
  double margin = fmax(0.5, 0.25 * fmax(hi[0] - lo[0], hi[1] - lo[1]));
  view_grid g;
  g.x0 = lo[0] - margin, g.y0 = lo[1] - margin;
  g.d = fmax(hi[0] - lo[0], hi[1] - lo[1]) + 2 * margin;
  g.d /= VIEW_FIELD_N - 1;
  g.nx = (int)ceil((hi[0] - lo[0] + 2 * margin) / g.d - 1e-9) + 1;
  g.ny = (int)ceil((hi[1] - lo[1] + 2 * margin) / g.d - 1e-9) + 1;
  if (g.nx > VIEW_FIELD_N) g.nx = VIEW_FIELD_N;
  if (g.ny > VIEW_FIELD_N) g.ny = VIEW_FIELD_N;
  return g;
}

/* h and its gradient at grid point (i, j); 0 when defined. */
static int sample(const view_ground *g, const view_grid *G, int i, int j, double h[6]) {
  int rc = g->height_fn(G->x0 + i * G->d, G->y0 + j * G->d, h, g->height_user);
  return rc == 0 && isfinite(h[0]) && isfinite(h[1]) && isfinite(h[2]) ? 0 : -1;
}

void view_field_json(FILE *out, const view_frames *f, const view_ground *g) {
  view_grid G = view_field_grid(f);
  fprintf(out, "{\"kind\":\"heightfield\",\"x0\":%.17g,\"y0\":%.17g,\"d\":%.17g,\"nx\":%d,"
          "\"ny\":%d,\"z\":[", G.x0, G.y0, G.d, G.nx, G.ny);
  for (int j = 0; j < G.ny; j++)
    for (int i = 0; i < G.nx; i++) {
      double h[6];
      if (i || j) fputc(',', out);
      if (sample(g, &G, i, j, h) == 0) fprintf(out, "%.9g", h[0]);
      else fputs("null", out);
    }
  fputs("]}", out);
}

int view_field_mesh(const view_frames *f, const view_ground *g, view_mesh *m) {
  view_grid G = view_field_grid(f);
  int nv = G.nx * G.ny, ni = 0;
  char *ok = malloc((size_t)nv);
  if (!ok || view_alloc_mesh(m, nv, 6 * (G.nx - 1) * (G.ny - 1)) != 0) return free(ok), -1;
  for (int j = 0; j < G.ny; j++)
    for (int i = 0; i < G.nx; i++) {
      double h[6];
      int v = j * G.nx + i;
      ok[v] = sample(g, &G, i, j, h) == 0;
      if (!ok[v]) h[0] = h[1] = h[2] = 0.0;
      double s = sqrt(1 + h[1] * h[1] + h[2] * h[2]);
      float p[3] = {(float)(G.x0 + i * G.d), (float)(G.y0 + j * G.d), (float)h[0]};
      float n[3] = {(float)(-h[1] / s), (float)(-h[2] / s), (float)(1 / s)};
      memcpy(m->pos + 3 * v, p, sizeof p), memcpy(m->normal + 3 * v, n, sizeof n);
    }
  for (int j = 0; j + 1 < G.ny; j++)
    for (int i = 0; i + 1 < G.nx; i++) {
      int a = j * G.nx + i, b = a + 1, c = a + G.nx, d = c + 1;
      if (!ok[a] || !ok[b] || !ok[c] || !ok[d]) continue;
      unsigned short q[6] = {(unsigned short)a, (unsigned short)b, (unsigned short)d,
                             (unsigned short)a, (unsigned short)d, (unsigned short)c};
      memcpy(m->index + ni, q, sizeof q);
      ni += 6;
    }
  m->ni = ni;
  free(ok);
  return 0;
}
