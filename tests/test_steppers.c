/* placeholder: replaced by the real test; fails until then */
#include <stdio.h>
int main(void) { fprintf(stderr, "test_steppers: not written yet\n"); return 1; }
