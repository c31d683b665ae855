/* Text helpers (core/text.h): errno texts through strerror_r in either of its variants (the
 * XSI one returns int and fills the buffer, the GNU one returns the text: _Generic on its
 * return type picks the right reading at compile time), and names copied into fixed buffers
 * with an ellipsis when they are cut. */
#include "core/text.h"

#include <stdio.h>
#include <string.h>

static const char *gnu_text(const char *r, int err, char *buf, size_t len) {
  if (r) return r;
  snprintf(buf, len, "error %d", err);
  return buf;
}

static const char *xsi_text(int r, int err, char *buf, size_t len) {
  if (r != 0 || !buf[0]) snprintf(buf, len, "error %d", err);
  return buf;
}

const char *ap_core_errno_text(int err, char *buf, size_t len) {
  if (!buf || len == 0) return "error";
  buf[0] = '\0';
  return _Generic(strerror_r(err, buf, len), int: xsi_text, default: gnu_text)(
      strerror_r(err, buf, len), err, buf, len);
}

void ap_core_prefix(char *msg, size_t len, const char *prefix) {
  if (!msg || len < 4) return;
  size_t np = strlen(prefix), nm = strnlen(msg, len - 1);
  if (np >= len - 4) np = len - 4;
  size_t keep = nm < len - 1 - np ? nm : len - 1 - np;
  memmove(msg + np, msg, keep);
  memcpy(msg, prefix, np);
  msg[np + keep] = '\0';
  if (keep < nm) memcpy(msg + len - 4, "...", 4);
}

int ap_core_copy_name(char *dst, size_t size, const char *src) {
  size_t n = strlen(src);
  if (n < size) {
    memcpy(dst, src, n + 1);
    return 0;
  }
  size_t keep = size - 4;   /* room for "..." and the terminator */
  while (keep > 0 && ((unsigned char)src[keep] & 0xC0) == 0x80) keep--;   /* UTF-8 lead */
  memcpy(dst, src, keep);
  memcpy(dst + keep, "...", 4);
  return 1;
}
