/* appell view: write the self-contained HTML page (docs/viewer.md).
 *
 * Layout of the file: the page's CSS; three.js and its OrbitControls (from Debian's libjs-three,
 * inlined at build time: tools/viewer/embed.py); the run as one JSON object in a
 * <script type="application/json" id="appell-data"> element; the page's own script
 * (tools/viewer/viewer.js), which reads that object. Arrays of numbers are base64 of
 * little-endian IEEE doubles, so the page holds exactly the doubles computed here: times (nf),
 * poses (nf x nb x 7: x y z, qw qx qy qz), contact points (nf x nb x 3), contact forces
 * (nf x nb x 3, when drawn) and each plotted channel (nf). The run record (OUT.run.json) goes in
 * as a JSON string, parsed by the page. Nothing is fetched at view time. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "view.h"

void view_base64(FILE *out, const unsigned char *p, size_t n) {
  static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  char buf[4];
  for (size_t i = 0; i < n; i += 3) {
    uint32_t v = (uint32_t)p[i] << 16;
    if (i + 1 < n) v |= (uint32_t)p[i + 1] << 8;
    if (i + 2 < n) v |= p[i + 2];
    buf[0] = tab[v >> 18 & 63], buf[1] = tab[v >> 12 & 63];
    buf[2] = i + 1 < n ? tab[v >> 6 & 63] : '=';
    buf[3] = i + 2 < n ? tab[v & 63] : '=';
    fwrite(buf, 1, 4, out);
  }
}

/* n doubles, x[i * stride], as base64 of little-endian bytes, in quotes. */
static void doubles(FILE *out, const double *x, size_t n, size_t stride) {
  unsigned char chunk[8 * 384];
  size_t fill = 0;
  fputc('"', out);
  for (size_t i = 0; i < n; i++) {
    uint64_t u;
    memcpy(&u, &x[i * stride], 8);
    for (int b = 0; b < 8; b++) chunk[fill++] = (unsigned char)(u >> (8 * b));
    if (fill == sizeof chunk) view_base64(out, chunk, fill), fill = 0;
  }
  view_base64(out, chunk, fill);
  fputc('"', out);
}

/* A JSON string that is also safe inside a <script> element. */
static void jstring(FILE *out, const char *s) {
  fputc('"', out);
  for (; s && *s; s++) {
    unsigned char ch = (unsigned char)*s;
    if (ch == '"' || ch == '\\') fprintf(out, "\\%c", ch);
    else if (ch < 0x20 || ch == '<' || ch == '>' || ch == '&') fprintf(out, "\\u%04x", ch);
    else fputc(ch, out);
  }
  fputc('"', out);
}

static void vec(FILE *out, const double *x, int n) {
  fputc('[', out);
  for (int i = 0; i < n; i++) fprintf(out, i ? ",%.17g" : "%.17g", x[i]);
  fputc(']', out);
}

static void body_json(FILE *out, const view_body *b, int forces) {
  static const char *const shapes[] = {"none", "point", "sphere", "ellipsoid", "disk", "torus"};
  static const char *const visuals[] = {"none", "box", "capsule", "sphere"};
  int sk = (int)b->shape.kind >= 0 && (int)b->shape.kind <= 5 ? (int)b->shape.kind : 0;
  int vk = (int)b->visual.kind >= 0 && (int)b->visual.kind <= 3 ? (int)b->visual.kind : 0;
  fputs("{\"name\":", out);
  jstring(out, b->name);
  fprintf(out, ",\"shape\":{\"kind\":\"%s\",\"radius\":%.17g,\"tube\":%.17g,\"axes\":", shapes[sk],
          b->shape.radius, b->shape.tube);
  vec(out, b->shape.semi_axes, 3);
  fprintf(out, "},\"visual\":{\"kind\":\"%s\",\"size\":", visuals[vk]);
  vec(out, b->visual.size, 3);
  fprintf(out, ",\"radius\":%.17g,\"length\":%.17g,\"axis\":%d,\"at\":", b->visual.radius,
          b->visual.length, b->visual.axis);
  vec(out, b->visual.at, 3);
  fprintf(out, "},\"contact\":%d,\"force\":%d}", b->contact,
          forces && b->contact && b->force_col[0] >= 0 && b->force_col[2] >= 0);
}

static void forces_json(FILE *out, const view_frames *f, const view_csv *csv) {
  size_t n = (size_t)f->nf * (size_t)f->nb * 3;
  double *F = calloc(n + 1, sizeof *F);
  if (!F) return;
  for (long r = 0; r < f->nf; r++)
    for (int b = 0; b < f->nb; b++)
      for (int i = 0; i < 3 && f->bodies[b].force_col[i] >= 0; i++) {
        double x = csv->rows[(size_t)r * (size_t)csv->ncols + (size_t)f->bodies[b].force_col[i]];
        F[((size_t)r * (size_t)f->nb + (size_t)b) * 3 + (size_t)i] = isfinite(x) ? x : 0.0;
      }
  fputs(",\"forces\":", out);
  doubles(out, F, n, 1);
  free(F);
}

static void data_json(FILE *out, const view_frames *f, const view_csv *csv, const view_page *p) {
  fputs("{\"scene\":", out);
  jstring(out, p->title ? p->title : f->scene);
  fprintf(out, ",\"nf\":%ld,\"nb\":%d,\"t\":", f->nf, f->nb);
  doubles(out, f->t, (size_t)f->nf, 1);
  fputs(",\"bodies\":[", out);
  for (int b = 0; b < f->nb; b++) {
    if (b) fputc(',', out);
    body_json(out, &f->bodies[b], p->forces);
  }
  fputs("],\"pose\":", out);
  doubles(out, f->pose, (size_t)f->nf * (size_t)f->nb * 7, 1);
  fputs(",\"contact\":", out);
  doubles(out, f->contact, (size_t)f->nf * (size_t)f->nb * 3, 1);
  if (p->forces) forces_json(out, f, csv);
  fputs(",\"grounds\":", out);
  view_grounds_json(out, f);
  fputs(",\"plots\":[", out);
  for (int i = 0; i < p->nplots; i++) {
    int c = view_csv_column(csv, p->plots[i]);
    fputs(i ? ",{\"name\":" : "{\"name\":", out);
    jstring(out, p->plots[i]);
    fputs(",\"data\":", out);
    doubles(out, csv->rows + c, (size_t)csv->nrows, (size_t)csv->ncols);
    fputc('}', out);
  }
  fputs("],\"record\":", out);
  if (p->record) jstring(out, p->record);
  else fputs("null", out);
  fputc('}', out);
}

static const char body_html[] =
    "<div id=\"app\"><div id=\"view3d\"></div><div id=\"side\"><div id=\"info\"></div>"
    "<div id=\"plots\"></div></div></div>\n"
    "<div id=\"bar\"><button id=\"play\" title=\"play / pause (space)\">play</button>"
    "<div id=\"timeline\"><input id=\"scrub\" type=\"range\" min=\"0\" value=\"0\" step=\"1\">"
    "<div id=\"marks\"></div></div><span id=\"time\"></span>"
    "<label>speed <select id=\"speed\"></select></label>"
    "<label><input id=\"loop\" type=\"checkbox\" checked> loop</label>"
    "<label>follow <select id=\"follow\"><option value=\"-1\">none</option></select></label>"
    "</div>\n";

int view_write_page(FILE *out, const view_frames *f, const view_csv *csv, const view_page *p) {
  fputs("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>", out);
  for (const char *s = p->title ? p->title : f->scene; s && *s; s++)
    if (*s != '<' && *s != '&') fputc(*s, out);
  fputs(" - appell view</title>\n<meta name=\"generator\" content=\"appell view\">\n<style>\n",
        out);
  fwrite(view_viewer_css, 1, view_viewer_css_len, out);
  fputs("</style></head><body>\n", out);
  fputs(body_html, out);
  fputs("<script>\n", out);
  fwrite(view_three_js, 1, view_three_js_len, out);
  fputs("\n</script>\n<script>\n", out);
  fwrite(view_orbit_js, 1, view_orbit_js_len, out);
  fputs("\n</script>\n<script type=\"application/json\" id=\"appell-data\">", out);
  data_json(out, f, csv, p);
  fputs("</script>\n<script>\n", out);
  fwrite(view_viewer_js, 1, view_viewer_js_len, out);
  fputs("\n</script>\n</body></html>\n", out);
  return ferror(out) ? -1 : 0;
}
