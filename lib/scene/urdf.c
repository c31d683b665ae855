/* URDF import: read the XML with libxml2 into a ur_robot (urdf_int.h) and check it, then hand
 * it to the scene writer (urdf_emit.c).
 *
 * What is read: <robot name>; each <link name> with <inertial> (<origin xyz rpy>, <mass
 * value>, <inertia ixx ixy ixz iyy iyz izz>) and the first <collision> whose <geometry> is a
 * <sphere radius> or a <cylinder radius length> (with its <origin>); each <joint name type>
 * with <parent link>, <child link>, <origin>, <axis xyz> (default 1 0 0), <limit lower upper>
 * and <dynamics damping>. Everything else (visuals, meshes, boxes, transmissions, gazebo
 * tags) is skipped. Checks, each reported as "FILE:LINE: <element name='...'>: what": a link
 * without inertial or with a mass that is not positive, an unknown joint type, a parent or
 * child that is no link, a zero axis, limits in the wrong order, a link with two parents, a
 * cycle of joints, more than one root, wheels that are no link or have no round collision.
 * XML syntax errors carry libxml2's line and column. The file is read as scenes are (at most
 * 16 MiB, ap_scene_read); no network access, no entity expansion. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <libxml/parser.h>

#include "appell/scene.h"
#include "core/defcheck.h"
#include "scene/scene_int.h"
#include "scene/urdf_int.h"


int ur_err(ur_ctx *c, const xmlNode *at, const char *fmt, ...) {
  if (c->status != AP_OK) return c->status;
  char what[600];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(what, sizeof what, fmt, ap);
  va_end(ap);
  xmlChar *name = at ? xmlGetProp(at, BAD_CAST "name") : NULL;
  if (c->msg && c->msg_len)
    snprintf(c->msg, c->msg_len, "%s:%ld: <%s%s%s%s>: %s", c->file,
             at ? xmlGetLineNo(at) : 1L, at ? (const char *)at->name : "robot",
             name ? " name='" : "", name ? (const char *)name : "", name ? "'" : "", what);
  xmlFree(name);
  c->status = AP_ERR_ARG;
  return AP_ERR_ARG;
}

static int is(const xmlNode *n, const char *name) {
  return n->type == XML_ELEMENT_NODE && strcmp((const char *)n->name, name) == 0;
}

static xmlNode *child(const xmlNode *n, const char *name) {
  for (xmlNode *k = n ? n->children : NULL; k; k = k->next)
    if (is(k, name)) return k;
  return NULL;
}

/* Attribute attr of n as count numbers (missing: def, or an error when def is NULL). */
static int numbers(ur_ctx *c, const xmlNode *n, const char *attr, int count, const double *def,
                   double *out) {
  xmlChar *text = xmlGetProp(n, BAD_CAST attr);
  if (!text) {
    if (!def) return ur_err(c, n, "attribute '%s' is missing", attr);
    memcpy(out, def, (size_t)count * sizeof *out);
    return AP_OK;
  }
  const char *s = (const char *)text;
  char *end = NULL;
  int i = 0;
  for (; i < count; i++, s = end) {
    out[i] = strtod(s, &end);
    if (end == s || !isfinite(out[i])) break;
  }
  while (i == count && (*s == ' ' || *s == '\t' || *s == '\n' || *s == '\r')) s++;
  int ok = i == count && *s == '\0';
  if (!ok) ur_err(c, n, "%s='%s' is not %d finite number%s", attr, (const char *)text, count,
                  count > 1 ? "s" : "");
  xmlFree(text);
  return ok ? AP_OK : AP_ERR_ARG;
}

static int origin(ur_ctx *c, const xmlNode *parent, ur_pose *pose) {
  static const double zero[3] = {0, 0, 0};
  double rpy[3];
  const xmlNode *o = child(parent, "origin");
  memset(pose->p, 0, sizeof pose->p);
  pose->q[0] = 1, pose->q[1] = pose->q[2] = pose->q[3] = 0;
  if (!o) return AP_OK;
  if (numbers(c, o, "xyz", 3, zero, pose->p) || numbers(c, o, "rpy", 3, zero, rpy))
    return AP_ERR_ARG;
  ur_pose_rpy(rpy, pose->q);
  return AP_OK;
}

/* The scene's name for a URDF name: letters, digits, '_' and '-', not starting with a digit
 * or '-'; other characters become '_'. */
static int scene_name(ur_ctx *c, const xmlNode *n, char *out, char *urdf_out) {
  xmlChar *text = xmlGetProp(n, BAD_CAST "name");
  if (!text || !text[0]) {
    xmlFree(text);
    return ur_err(c, n, "attribute 'name' is missing");
  }
  size_t len = strlen((const char *)text);
  if (len >= 128) {
    xmlFree(text);
    return ur_err(c, n, "the name is longer than 127 characters");
  }
  memcpy(urdf_out, text, len + 1);
  for (size_t i = 0; i <= len; i++) {
    char ch = (char)text[i];
    int ok = (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || ch == '_' || ch == '\0' ||
             (i > 0 && ((ch >= '0' && ch <= '9') || ch == '-'));
    out[i] = ok ? ch : '_';
  }
  xmlFree(text);
  return AP_OK;
}

static int read_inertial(ur_ctx *c, const xmlNode *n, ur_link *l) {
  const xmlNode *in = child(n, "inertial");
  if (!in) return AP_OK;
  l->has_inertial = 1;
  const xmlNode *m = child(in, "mass"), *it = child(in, "inertia");
  if (!m) return ur_err(c, in, "<mass value=...> is missing");
  if (!it) return ur_err(c, in, "<inertia ixx=... iyy=... izz=...> is missing");
  if (origin(c, in, &l->inertial) || numbers(c, m, "value", 1, NULL, &l->mass))
    return AP_ERR_ARG;
  if (!(l->mass > 0)) return ur_err(c, m, "the mass %g is not positive", l->mass);
  static const char *const keys[6] = {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"};
  static const double zero = 0;
  for (int i = 0; i < 6; i++)
    if (numbers(c, it, keys[i], 1, (i == 1 || i == 2 || i == 4) ? &zero : NULL, &l->I[i]))
      return AP_ERR_ARG;
  const double *I = l->I;
  double M[9] = {I[0], I[1], I[2], I[1], I[3], I[4], I[2], I[4], I[5]}, mn[3];
  sc_leading_minors(M, mn);
  if (!(mn[0] > 0 && mn[1] > 0 && mn[2] > 0))
    return ur_err(c, it, "the inertia tensor is not positive definite (leading minors %g, %g, "
                  "%g; all must be positive)", mn[0], mn[1], mn[2]);
  return AP_OK;
}

/* The first collision sphere or cylinder. */
static int read_collision(ur_ctx *c, const xmlNode *n, ur_link *l) {
  for (const xmlNode *k = n->children; k; k = k->next) {
    const xmlNode *g = is(k, "collision") ? child(k, "geometry") : NULL;
    const xmlNode *s = g ? child(g, "sphere") : NULL, *y = g ? child(g, "cylinder") : NULL;
    if (!s && !y) continue;
    l->shape = s ? UR_SHAPE_SPHERE : UR_SHAPE_CYLINDER;
    l->shape_line = (int)xmlGetLineNo(s ? s : y);
    if (origin(c, k, &l->shape_pose) || numbers(c, s ? s : y, "radius", 1, NULL, &l->radius) ||
        (y && numbers(c, y, "length", 1, NULL, &l->length)))
      return AP_ERR_ARG;
    if (!(l->radius > 0)) return ur_err(c, s ? s : y, "the radius %g is not positive", l->radius);
    if (y && !(l->length >= 0)) return ur_err(c, y, "the length %g is negative", l->length);
    return AP_OK;
  }
  return AP_OK;
}

static int read_link(ur_ctx *c, const xmlNode *n, ur_link *l) {
  memset(l, 0, sizeof *l);
  l->parent_joint = -1;
  l->line = (int)xmlGetLineNo(n);
  l->inertial.q[0] = l->shape_pose.q[0] = 1;
  if (scene_name(c, n, l->name, l->urdf_name)) return AP_ERR_ARG;
  l->world = strcmp(l->urdf_name, "world") == 0;
  if (strcmp(l->name, "ground") == 0)
    return ur_err(c, n, "'ground' is the scene's name of the fixed world: rename the link");
  if (read_inertial(c, n, l) || read_collision(c, n, l)) return AP_ERR_ARG;
  if (!l->has_inertial && !l->world)
    return ur_err(c, n, "the link has no <inertial>: every link but 'world' needs a mass and "
                  "an inertia (a massless link cannot be simulated)");
  return AP_OK;
}

/* <parent link=...> or <child link=...>: the link index. */
static int link_ref(ur_ctx *c, const ur_robot *r, const xmlNode *j, const char *role, int *out) {
  const xmlNode *e = child(j, role);
  if (!e) return ur_err(c, j, "<%s link=...> is missing", role);
  xmlChar *name = xmlGetProp(e, BAD_CAST "link");
  if (!name) return ur_err(c, e, "attribute 'link' is missing");
  *out = ur_find_link(r, (const char *)name);
  if (*out < 0) {
    const char *names[256];
    int cnt = r->nlinks < 256 ? r->nlinks : 256;
    for (int i = 0; i < cnt; i++) names[i] = r->links[i].urdf_name;
    const char *s = ap_suggest((const char *)name, names, cnt);
    ur_err(c, e, "no link named '%s'%s%s%s", (const char *)name, s ? " (did you mean '" : "",
           s ? s : "", s ? "'?)" : "");
  }
  xmlFree(name);
  return *out < 0 ? AP_ERR_ARG : AP_OK;
}

static int joint_type(ur_ctx *c, const xmlNode *n, int *type) {
  static const char *const types[] = {"revolute", "continuous", "prismatic",
                                      "fixed",    "floating",   "planar"};
  xmlChar *t = xmlGetProp(n, BAD_CAST "type");
  if (!t) return ur_err(c, n, "attribute 'type' is missing");
  *type = -1;
  for (int i = 0; i < 6; i++)
    if (strcmp((const char *)t, types[i]) == 0) *type = i;
  if (*type < 0) {
    const char *s = ap_suggest((const char *)t, types, 6);
    ur_err(c, n, "unknown joint type '%s' (%s%s%s)", (const char *)t,
           s ? "did you mean '" : "one of revolute, continuous, prismatic, fixed, floating, "
               "planar", s ? s : "", s ? "'?" : "");
  }
  xmlFree(t);
  return *type < 0 ? AP_ERR_ARG : AP_OK;
}

static int read_axis(ur_ctx *c, const xmlNode *n, ur_joint *j) {
  static const double def[3] = {1, 0, 0};
  const xmlNode *a = child(n, "axis");
  if (!a) {
    memcpy(j->axis, def, sizeof def);
    return AP_OK;
  }
  if (numbers(c, a, "xyz", 3, def, j->axis)) return AP_ERR_ARG;
  double len = sqrt(j->axis[0] * j->axis[0] + j->axis[1] * j->axis[1] + j->axis[2] * j->axis[2]);
  int needs = j->type != UR_FIXED && j->type != UR_FLOATING;
  if (needs && !(len > 1e-12))
    return ur_err(c, a, "the axis (%g, %g, %g) is zero: it needs a direction", j->axis[0],
                  j->axis[1], j->axis[2]);
  for (int i = 0; needs && i < 3; i++) j->axis[i] /= len;
  return AP_OK;
}

static int read_limits(ur_ctx *c, const xmlNode *n, ur_joint *j) {
  static const double zero = 0;
  const xmlNode *d = child(n, "dynamics"), *l = child(n, "limit");
  if (d && numbers(c, d, "damping", 1, &zero, &j->damping)) return AP_ERR_ARG;
  if (!(j->damping >= 0)) return ur_err(c, d, "the damping %g is negative", j->damping);
  if (!l || (j->type != UR_REVOLUTE && j->type != UR_PRISMATIC)) return AP_OK;
  if (numbers(c, l, "lower", 1, &zero, &j->lower) || numbers(c, l, "upper", 1, &zero, &j->upper))
    return AP_ERR_ARG;
  if (j->lower > j->upper)
    return ur_err(c, l, "the lower limit %g is above the upper limit %g", j->lower, j->upper);
  j->has_limit = j->lower < j->upper;   /* URDF's lower = upper = 0: no limit given */
  return AP_OK;
}

static int read_joint(ur_ctx *c, ur_robot *r, const xmlNode *n, ur_joint *j) {
  memset(j, 0, sizeof *j);
  j->line = (int)xmlGetLineNo(n);
  if (scene_name(c, n, j->name, j->urdf_name) || joint_type(c, n, &j->type) ||
      link_ref(c, r, n, "parent", &j->parent) || link_ref(c, r, n, "child", &j->child) ||
      origin(c, n, &j->origin) || read_axis(c, n, j) || read_limits(c, n, j))
    return AP_ERR_ARG;
  if (j->parent == j->child) return ur_err(c, n, "the parent and the child are one link");
  ur_link *ch = &r->links[j->child];
  if (ch->world) return ur_err(c, n, "'world' is the fixed ground: it cannot be a child");
  if (ch->parent_joint >= 0)
    return ur_err(c, n, "link '%s' is already the child of joint '%s' (line %d): a link has "
                  "one parent", ch->urdf_name, r->joints[ch->parent_joint].urdf_name,
                  r->joints[ch->parent_joint].line);
  ch->parent_joint = (int)(j - r->joints);
  return AP_OK;
}

static int mark_wheels(ur_ctx *c, ur_robot *r, const ap_urdf_def *def, xmlNode *const *lnodes) {
  for (int w = 0; w < def->nwheels; w++) {
    const char *name = def->wheels ? def->wheels[w] : NULL;
    int i = name ? ur_find_link(r, name) : -1;
    if (i < 0) {
      const char *names[256];
      int cnt = r->nlinks < 256 ? r->nlinks : 256;
      for (int k = 0; k < cnt; k++) names[k] = r->links[k].urdf_name;
      const char *s = name ? ap_suggest(name, names, cnt) : NULL;
      snprintf(c->msg, c->msg_len, "%s: wheel '%s': the robot has no such link%s%s%s", c->file,
               name ? name : "(null)", s ? " (did you mean '" : "", s ? s : "", s ? "'?)" : "");
      return c->status = AP_ERR_ARG;
    }
    ur_link *l = &r->links[i];
    if (l->world) return ur_err(c, lnodes[i], "'world' is the ground: it cannot be a wheel");
    if (!l->shape)
      return ur_err(c, lnodes[i], "a wheel needs a <collision> cylinder or sphere (its radius "
                    "is the rolling radius)");
    if (def->wheel_shape == AP_URDF_WHEEL_TORUS && l->shape == UR_SHAPE_CYLINDER &&
        !(l->length > 0 && l->length < l->radius))
      return ur_err(c, lnodes[i], "a torus wheel needs a cylinder of positive length below "
                    "its radius (length %g, radius %g)", l->length, l->radius);
    l->wheel = 1;
  }
  return AP_OK;
}

static int count(const xmlNode *root, const char *name) {
  int n = 0;
  for (const xmlNode *k = root->children; k; k = k->next) n += is(k, name);
  return n;
}

/* Read the document into r (arrays allocated here) and check it. */
static int read_robot(ur_ctx *c, xmlNode *root, const ap_urdf_def *def, ur_robot *r,
                      xmlNode ***lnodes, xmlNode ***jnodes) {
  if (!is(root, "robot"))
    return ur_err(c, root, "the top element is <%s>, not <robot>", (const char *)root->name);
  xmlChar *name = xmlGetProp(root, BAD_CAST "name");
  snprintf(r->name, sizeof r->name, "%s", name ? (const char *)name : "robot");
  xmlFree(name);
  for (char *p = r->name; *p; p++)
    if (!((*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') || (*p >= '0' && *p <= '9') ||
          *p == '-'))
      *p = '_';
  int nl = count(root, "link"), nj = count(root, "joint");
  r->links = calloc((size_t)nl + 1, sizeof *r->links);
  r->joints = calloc((size_t)nj + 1, sizeof *r->joints);
  *lnodes = calloc((size_t)nl + 1, sizeof **lnodes);
  *jnodes = calloc((size_t)nj + 1, sizeof **jnodes);
  if (!r->links || !r->joints || !*lnodes || !*jnodes) return c->status = AP_ERR_NOMEM;
  for (xmlNode *k = root->children; k; k = k->next)
    if (is(k, "link")) {
      (*lnodes)[r->nlinks] = k;
      if (read_link(c, k, &r->links[r->nlinks++])) return AP_ERR_ARG;
    }
  if (ur_index_links(c, r, *lnodes)) return c->status;
  for (xmlNode *k = root->children; k; k = k->next)
    if (is(k, "joint")) {
      (*jnodes)[r->njoints] = k;
      if (read_joint(c, r, k, &r->joints[r->njoints++])) return AP_ERR_ARG;
    }
  if (ur_check_joint_names(c, r, *jnodes) || ur_check_tree(c, r, *jnodes, *lnodes) ||
      mark_wheels(c, r, def, *lnodes))
    return c->status;
  for (int j = 0; !r->links[r->root].world && j < r->njoints; j++)
    if (strcmp(r->joints[j].name, r->links[r->root].name) == 0)
      return ur_err(c, (*jnodes)[j], "the joint has the name of the root link '%s', which the "
                    "scene gives to the root's free joint: rename one", r->links[r->root].name);
  return AP_OK;
}

/* The first XML error of a parse (libxml2 reports later ones too, after recovering). */
typedef struct ur_xml_error {
  int set, line, col;
  char what[512];
} ur_xml_error;

static void first_error(void *user, xmlErrorPtr e) {
  xmlParserCtxt *x = user;
  ur_xml_error *f = x ? x->_private : NULL;
  if (!f || f->set || !e) return;
  f->set = 1, f->line = e->line > 0 ? e->line : 1, f->col = e->int2 > 0 ? e->int2 : 1;
  snprintf(f->what, sizeof f->what, "%s", e->message ? e->message : "not an XML document");
  f->what[strcspn(f->what, "\n")] = '\0';
}

/* Parse the text; XML syntax errors with libxml2's line and column. */
static xmlDoc *parse_xml(ur_ctx *c, const char *text, size_t len) {
  xmlParserCtxt *x = xmlNewParserCtxt();
  if (!x || !x->sax) {
    xmlFreeParserCtxt(x);
    c->status = AP_ERR_NOMEM;
    return NULL;
  }
  ur_xml_error f = {0, 1, 1, "not an XML document"};
  x->_private = &f;
  x->sax->serror = first_error;
  xmlDoc *doc = xmlCtxtReadMemory(x, text, (int)len, c->file, NULL,
                                  XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING |
                                      XML_PARSE_BIG_LINES);
  if (!doc || !xmlDocGetRootElement(doc) || f.set) {
    snprintf(c->msg, c->msg_len, "%s:%d:%d: XML syntax error: %s", c->file, f.line, f.col,
             f.what);
    c->status = AP_ERR_ARG;
    xmlFreeDoc(doc);
    doc = NULL;
  }
  xmlFreeParserCtxt(x);
  return doc;
}

ap_urdf_def ap_urdf_def_default(void) {
  ap_urdf_def def;
  memset(&def, 0, sizeof def);
  def.wheel_shape = AP_URDF_WHEEL_DISK;
  def.internal_check = AP_DEF_CHECK;
  return def;
}

static int convert(ur_ctx *c, const char *text, size_t len, const ap_urdf_def *def,
                   char **yaml, size_t *ylen) {
  xmlDoc *doc = parse_xml(c, text, len);
  if (!doc) return c->status;
  ur_robot r;
  memset(&r, 0, sizeof r);
  xmlNode **lnodes = NULL, **jnodes = NULL;
  int rc = read_robot(c, xmlDocGetRootElement(doc), def, &r, &lnodes, &jnodes);
  if (rc == AP_OK) rc = ur_emit(&r, def, c->file, yaml, ylen, c->msg, c->msg_len);
  free(r.links);
  free(r.joints);
  free(r.by_name);
  free(lnodes);
  free(jnodes);
  xmlFreeDoc(doc);
  return rc;
}

int ap_urdf_to_scene(const char *path, const ap_urdf_def *def, char **yaml, size_t *len,
                     char *msg, size_t msg_len) {
  char dummy[8];
  if (!msg || !msg_len) msg = dummy, msg_len = sizeof dummy;
  msg[0] = '\0';
  if (yaml) *yaml = NULL;
  if (len) *len = 0;
  if (!path || !yaml || !len) {
    snprintf(msg, msg_len, "ap_urdf_to_scene: path, yaml and len must not be NULL");
    return AP_ERR_ARG;
  }
  ap_urdf_def d = def ? *def : ap_urdf_def_default();
  if (d.internal_check != AP_DEF_CHECK || d.nwheels < 0 || (d.nwheels > 0 && !d.wheels)) {
    snprintf(msg, msg_len, "ap_urdf_to_scene: the definition was not made by "
             "ap_urdf_def_default(), or its wheels are inconsistent");
    return AP_ERR_ARG;
  }
  char *text = NULL;
  size_t tlen = 0;
  int rc = ap_scene_read(path, &text, &tlen, msg, msg_len);
  if (rc != AP_OK) return rc;
  if (tlen > (size_t)0x7fffffff) tlen = 0x7fffffff;
  ur_ctx c = {path, msg, msg_len, AP_OK};
  rc = convert(&c, text, tlen, &d, yaml, len);
  ap_scene_text_free(text);
  if (rc == AP_ERR_NOMEM && !msg[0]) snprintf(msg, msg_len, "%s: out of memory", path);
  return rc;
}
