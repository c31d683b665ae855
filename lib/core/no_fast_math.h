/* Refuse to build the library with -ffast-math or -ffinite-math-only.
 *
 * Every finiteness check of Appell (isfinite on callback results, NaN from a drive, the
 * overflow guards of the steppers' error norms) is folded to "finite" by a compiler that may
 * assume no NaN or infinity exists: the checks would vanish silently and a NaN would run
 * through a simulation unreported. lib/meson.build force-includes this header into every
 * library file (-include), so no file can forget it; tests/fast_math.sh checks that a file
 * compiled with -ffast-math against it fails. */
#ifndef AP_CORE_NO_FAST_MATH_H
#define AP_CORE_NO_FAST_MATH_H

#if defined(__FAST_MATH__) || (defined(__FINITE_MATH_ONLY__) && __FINITE_MATH_ONLY__)
#error "Appell must not be built with -ffast-math or -ffinite-math-only: they assume no NaN or infinity exists and remove every finiteness check of the library (remove the flag from CFLAGS / c_args)"
#endif

#endif
