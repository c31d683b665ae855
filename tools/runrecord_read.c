/* Reading a run record (tools/runrecord.h) for appell plot: a small JSON reader that walks the
 * top-level object, keeps status, message, t and the events' names and times, and skips every
 * other value (objects, arrays, strings with escapes, numbers, literals) without building
 * anything. Anything that is not JSON of that shape, or a record of another format, is
 * "no record" (-1): plotting never fails because of the record. */
#include <stdlib.h>
#include <string.h>

#include "runrecord.h"

typedef struct reader {
  const char *p, *end;
  int depth;
} reader;

static void ws(reader *r) {
  while (r->p < r->end && strchr(" \t\r\n", *r->p)) r->p++;
}

/* A string into out (len bytes, may be NULL: skipped); \uXXXX kept only for ASCII, other
 * escapes decoded; 0 or -1. */
static int string(reader *r, char *out, size_t len) {
  size_t n = 0;
  if (r->p >= r->end || *r->p != '"') return -1;
  for (r->p++; r->p < r->end && *r->p != '"'; r->p++) {
    char c = *r->p;
    if (c == '\\') {
      if (++r->p >= r->end) return -1;
      c = *r->p;
      if (c == 'u') {
        if (r->end - r->p < 5) return -1;
        char hex[5] = {r->p[1], r->p[2], r->p[3], r->p[4], 0};
        long u = strtol(hex, NULL, 16);
        c = u >= 0x20 && u < 0x7F ? (char)u : '?';
        r->p += 4;
      } else {
        c = c == 'n' ? ' ' : c == 't' ? ' ' : c == 'r' ? ' ' : c == 'b' || c == 'f' ? ' ' : c;
      }
    }
    if (out && n + 1 < len) out[n++] = c;
  }
  if (out && len) out[n] = '\0';
  return r->p < r->end ? (r->p++, 0) : -1;
}

static int value(reader *r, char *s, size_t len, double *x);

/* An array or object after its opening bracket; each member (key: value) or element skipped. */
static int compound(reader *r, char close) {
  if (++r->depth > 64) return -1;
  ws(r);
  if (r->p < r->end && *r->p == close) return r->p++, r->depth--, 0;
  for (;;) {
    ws(r);
    if (close == '}' && (string(r, NULL, 0) || (ws(r), r->p >= r->end || *r->p++ != ':')))
      return -1;
    if (value(r, NULL, 0, NULL)) return -1;
    ws(r);
    if (r->p >= r->end) return -1;
    char c = *r->p++;
    if (c == close) return r->depth--, 0;
    if (c != ',') return -1;
  }
}

/* Any value; a string goes to s, a number to *x (when given). */
static int value(reader *r, char *s, size_t len, double *x) {
  ws(r);
  if (r->p >= r->end) return -1;
  char c = *r->p;
  if (c == '"') return string(r, s, len);
  if (c == '{' || c == '[') return r->p++, compound(r, c == '{' ? '}' : ']');
  char *stop = NULL;
  double v = strtod(r->p, &stop);
  if (stop && stop > r->p && stop <= r->end) return r->p = stop, x ? (*x = v) : 0, 0;
  for (const char *lit[] = {"true", "false", "null"}, **l = lit; l < lit + 3; l++)
    if ((size_t)(r->end - r->p) >= strlen(*l) && strncmp(r->p, *l, strlen(*l)) == 0)
      return r->p += strlen(*l), 0;
  return -1;
}

/* The events array: each object's name and t. */
static int events(reader *r, cli_record_info *info) {
  ws(r);
  if (r->p >= r->end || *r->p != '[') return value(r, NULL, 0, NULL);
  r->p++;
  for (ws(r); r->p < r->end && *r->p != ']';) {
    if (*r->p != '{') return -1;
    r->p++;
    int i = info->nevents < CLI_RECORD_MAX_EVENTS ? info->nevents++ : -1;
    for (ws(r); r->p < r->end && *r->p != '}';) {
      char k[32];
      if (string(r, k, sizeof k) || (ws(r), r->p >= r->end || *r->p++ != ':')) return -1;
      int name = i >= 0 && strcmp(k, "name") == 0, t = i >= 0 && strcmp(k, "t") == 0;
      if (value(r, name ? info->event_name[i] : NULL, 64, t ? &info->event_t[i] : NULL))
        return -1;
      ws(r);
      if (r->p < r->end && *r->p == ',') r->p++, ws(r);
    }
    if (r->p >= r->end) return -1;
    r->p++, ws(r);
    if (r->p < r->end && *r->p == ',') r->p++, ws(r);
  }
  return r->p < r->end ? (r->p++, 0) : -1;
}

static int parse(reader *r, cli_record_info *info) {
  char format[64] = "";
  ws(r);
  if (r->p >= r->end || *r->p++ != '{') return -1;
  for (;;) {
    char k[64];
    ws(r);
    if (string(r, k, sizeof k) || (ws(r), r->p >= r->end || *r->p++ != ':')) return -1;
    int rc = strcmp(k, "format") == 0    ? value(r, format, sizeof format, NULL)
             : strcmp(k, "status") == 0  ? value(r, info->status, sizeof info->status, NULL)
             : strcmp(k, "message") == 0 ? value(r, info->message, sizeof info->message, NULL)
             : strcmp(k, "t") == 0       ? value(r, NULL, 0, &info->t)
             : strcmp(k, "events") == 0  ? events(r, info)
                                         : value(r, NULL, 0, NULL);
    if (rc) return -1;
    ws(r);
    if (r->p >= r->end) return -1;
    char c = *r->p++;
    if (c == '}') break;
    if (c != ',') return -1;
  }
  return strcmp(format, "appell run record 1") == 0 && info->status[0] ? 0 : -1;
}

int cli_record_read(const char *path, cli_record_info *info) {
  memset(info, 0, sizeof *info);
  FILE *f = fopen(path, "rb");
  if (!f) return -1;
  char *buf = malloc(1 << 20);
  size_t n = buf ? fread(buf, 1, (1 << 20) - 1, f) : 0;
  fclose(f);
  if (!buf) return -1;
  buf[n] = '\0';   /* strtod stops there */
  reader r = {buf, buf + n, 0};
  int rc = parse(&r, info);
  free(buf);
  if (rc) memset(info, 0, sizeof *info);
  return rc;
}
