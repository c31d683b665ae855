/* Small text helpers shared by the layers: thread-safe errno texts and names copied into
 * fixed buffers with visible truncation. */
#ifndef AP_CORE_TEXT_H
#define AP_CORE_TEXT_H

#include <stddef.h>

/* The text of errno value err (strerror_r: safe in any thread, unlike strerror), written to
 * buf (len bytes) or a static text of the C library; "error <err>" when it has none. */
const char *ap_core_errno_text(int err, char *buf, size_t len);

/* Copy src into dst (size bytes, size >= 4). When it does not fit, dst holds its first
 * bytes (never a cut UTF-8 sequence) and ends with "...", so a shortened name is visible
 * in every message that prints it. Returns 1 when src was shortened, else 0. */
int ap_core_copy_name(char *dst, size_t size, const char *src);

/* Put prefix in front of the message in msg (len bytes), in place. When the whole does not fit,
 * the message is cut and ends with "..." (len >= 4). */
void ap_core_prefix(char *msg, size_t len, const char *prefix);

#endif
