/* appell view and appell export: the run's frames (poses, contact points, plotted channels)
 * rebuilt from a CSV through the public API, and the writers of the HTML page and the glTF file
 * (docs/viewer.md). */
#ifndef APPELL_VIEW_H
#define APPELL_VIEW_H

#include <stdio.h>

#include <appell/appell.h>

/* A CSV of appell run: its header names and its rows (row-major, ncols per row). */
typedef struct view_csv {
  char **names;
  int ncols;
  double *rows;
  long nrows;
} view_csv;

/* One drawn body. */
typedef struct view_body {
  const char *name;        /* the model's */
  ap_shape shape;
  ap_scene_visual visual;
  int contact;             /* 1: the body has a contact point (trace on the ground) */
  int force_col[3];        /* CSV columns of BODY.contact.Fx, .Fy, .Fz, or -1 */
} view_body;

/* A ground surface to draw (tools/view_ground.c): the plane normal . p = offset, a sphere, or
 * a height field z = h(x, y) (field: sampled on a grid about the motion, view_field.c). */
#define VIEW_MAX_GROUNDS 8
typedef struct view_ground {
  int sphere;              /* 0 plane, 1 sphere */
  double normal[3];        /* plane: unit normal, out of the ground */
  double offset;           /* plane: normal . p (m) */
  double center[3];        /* sphere: centre (m) */
  double radius;           /* sphere: radius (m) */
  int inside;              /* sphere: rolled on from inside (a bowl) */
  int field;               /* 1: a height field (the model's function and its user pointer) */
  ap_height_fn height_fn;
  void *height_user;
} view_ground;

/* Everything a page or an export shows, one frame per CSV row. */
typedef struct view_frames {
  const char *scene;       /* the scene's name */
  int nb;
  view_body *bodies;
  long nf;                 /* frames */
  double *t;               /* nf times (s) */
  double *pose;            /* nf x nb x 7: origin x y z (m), quaternion w x y z (world) */
  double *contact;         /* nf x nb x 3: contact point (m), 0 for bodies without contact */
  int ng;                  /* the distinct grounds of the rolling and knife-edge constraints */
  view_ground ground[VIEW_MAX_GROUNDS];   /* (the plane z = 0 when the scene has none) */
} view_frames;

/* The scene's grounds into f->ground (view_ground.c). */
void view_grounds(const ap_scene *sc, view_frames *f);
/* The grounds as JSON: [{"kind":"plane","normal":[..],"offset":d} or {"kind":"sphere",
 * "center":[..],"radius":r,"inside":0|1}, ...]. */
void view_grounds_json(FILE *out, const view_frames *f);

/* Read an appell CSV: 0, or an exit code with a message naming the file and line. */
int view_csv_read(const char *cmd, const char *path, view_csv *c);
void view_csv_free(view_csv *c);
int view_csv_column(const view_csv *c, const char *name);   /* -1 when absent */

/* Poses of every body at every row of csv: the coordinates columns into q, the kinematics at
 * (t, q), ap_body_get_state. 0, or an exit code with a message (a missing coordinate column). */
int view_frames_build(const char *cmd, ap_scene *sc, const view_csv *csv, view_frames *f);
void view_frames_free(view_frames *f);

/* Page options. */
typedef struct view_page {
  const char *title;
  const char *const *plots;   /* channel names to plot, nplots */
  int nplots;
  const char *record;         /* the run record's JSON text (OUT.run.json), or NULL */
  int forces;                 /* draw the contact-force arrows */
} view_page;

/* Write the self-contained HTML page; 0 or -1 on a write error. */
int view_write_page(FILE *out, const view_frames *f, const view_csv *csv, const view_page *p);

/* Base64 of n bytes (RFC 4648, with padding) to out. */
void view_base64(FILE *out, const unsigned char *p, size_t n);

/* The inlined files (generated at build time by tools/viewer/embed.py). */
extern const unsigned char view_three_js[], view_orbit_js[], view_viewer_js[], view_viewer_css[];
extern const unsigned long view_three_js_len, view_orbit_js_len, view_viewer_js_len,
    view_viewer_css_len;

/* Triangle meshes of the shapes (tools/view_mesh.c), in body axes. */
typedef struct view_mesh {
  float *pos, *normal, *color;   /* nv x 3: m, unit normal, RGB in [0, 1] */
  unsigned short *index;   /* ni */
  int nv, ni;
} view_mesh;
/* The mesh of body b's shape and visual together (a small triad of boxes when it has neither);
 * 0 or -1 out of memory. */
int view_mesh_body(const view_body *b, view_mesh *m);
void view_mesh_free(view_mesh *m);
/* The mesh of ground g in world axes: a square of the plane about the motion's bounding box
 * (projected onto it, with a margin), or a UV sphere (normals outward, inward for a bowl);
 * 0 or -1 out of memory (view_ground.c). */
int view_mesh_ground(const view_frames *f, const view_ground *g, view_mesh *m);

/* A height field's grid about the motion (view_field.c): nx x ny points from (x0, y0) every
 * d (m), at most VIEW_FIELD_N a side; its JSON {"kind":"heightfield","x0":..,"y0":..,"d":..,
 * "nx":..,"ny":..,"z":[x fastest; null where h is not defined]} and its mesh (0, or -1 out of
 * memory). */
#define VIEW_FIELD_N 121
typedef struct view_grid {
  double x0, y0, d;
  int nx, ny;
} view_grid;
view_grid view_field_grid(const view_frames *f);
/* A ground mesh of nv vertices (ground colour) and ni indices (view_ground.c). */
int view_alloc_mesh(view_mesh *m, int nv, int ni);
void view_field_json(FILE *out, const view_frames *f, const view_ground *g);
int view_field_mesh(const view_frames *f, const view_ground *g, view_mesh *m);

/* The glTF binary of f (tools/export_gltf.c); 0, or -1 out of memory or on a failed write. */
int view_write_gltf(FILE *out, const view_frames *f);

int cmd_view(int argc, char **argv);
int cmd_export(int argc, char **argv);

#endif
