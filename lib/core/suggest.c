/* The closest name to a misspelt one, for "did you mean" messages (the scene reader's unknown
 * keys and names, the linearizer's unknown state names).
 *
 * Distance: optimal string alignment, case-insensitive: insertions, deletions, substitutions
 * and swaps of two neighbouring letters each cost 1. A name is suggested when it is the
 * closest and within 1 edit for words of up to 4 letters, 2 up to 8, else 3. */
#include <ctype.h>
#include <string.h>

#include "core/core.h"

static int edit_distance(const char *a, const char *b) {
  size_t la = strlen(a), lb = strlen(b);
  if (la > 63 || lb > 63) return 99;
  int d[64][64];
  for (size_t i = 0; i <= la; i++) d[i][0] = (int)i;
  for (size_t j = 0; j <= lb; j++) d[0][j] = (int)j;
  for (size_t i = 1; i <= la; i++)
    for (size_t j = 1; j <= lb; j++) {
      int cost = tolower((unsigned char)a[i - 1]) != tolower((unsigned char)b[j - 1]);
      int best = d[i - 1][j - 1] + cost;
      if (d[i - 1][j] + 1 < best) best = d[i - 1][j] + 1;
      if (d[i][j - 1] + 1 < best) best = d[i][j - 1] + 1;
      int swap = i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1];
      if (swap && d[i - 2][j - 2] + 1 < best) best = d[i - 2][j - 2] + 1;
      d[i][j] = best;
    }
  return d[la][lb];
}

const char *ap_suggest(const char *word, const char *const *keys, int count) {
  const char *best = NULL;
  int bd = 99;
  for (int i = 0; word && keys && (count < 0 ? keys[i] != NULL : i < count); i++) {
    if (!keys[i]) continue;
    int d = edit_distance(word, keys[i]);
    if (d < bd) bd = d, best = keys[i];
  }
  if (!word) return NULL;
  int allow = (int)strlen(word) <= 4 ? 1 : (int)strlen(word) <= 8 ? 2 : 3;
  return bd <= allow ? best : NULL;
}
