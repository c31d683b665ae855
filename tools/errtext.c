/* The text of an errno value for the CLI's messages, safe in any thread: strerror shares one
 * static buffer (the sweep's workers and the library's threads may format at the same time),
 * so the texts come from POSIX's strerror_r into the caller's buffer. This file asks for the
 * POSIX variant only (no _GNU_SOURCE: glibc's GNU variant returns a char * instead of int). */
#undef _GNU_SOURCE
#include <stdio.h>
#include <string.h>

#include "cli.h"

const char *cli_errno_text(int err, char *buf, size_t len) {
  if (!buf || len == 0) return "unknown error";
  buf[0] = '\0';
  if (strerror_r(err, buf, len) != 0 || !buf[0]) snprintf(buf, len, "error %d", err);
  return buf;
}
