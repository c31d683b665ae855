/* Appell's generic scalar: one source, compiled for double and for complex-step numbers.
 *
 * Why. Linearization needs derivatives of the reduced equations exact to round-off. The
 * complex-step method gives them: evaluate f at x + i h dx with a tiny real h; then
 * Im f(x + i h dx) / h = f'(x) dx to round-off (no subtractive cancellation), provided every
 * operation on the way is the analytic continuation of its real counterpart. With h so small
 * that h^2 underflows against the values (AP_CS_STEP), complex arithmetic is exactly dual-number
 * arithmetic: real parts are the double results, imaginary parts carry the derivative.
 *
 * The convention (lib/linalg, and the per-evaluation code of lib/core, lib/model and the
 * linearization's reduced equations; core/core.h says how the data is mirrored):
 *  - A file that wants both versions is written once with the type ap_sc and the SC_* macros
 *    below, and compiled twice: as itself (double, the normal names) and from a one-line
 *    wrapper "#define AP_SC_COMPLEX 1 / #include "dir/file.c"" (complex-step, every public
 *    function renamed by AP_SC(name) -> name_cs). Static helpers keep their names (separate
 *    translation units). Internal shared fragments that hold static kernels end in ".inc".
 *  - Values go through + - * / and the SC_* functions only. The plain operators are C99
 *    complex arithmetic for ap_sc = double _Complex, so the double build's code is the old code
 *    token for token (its speed is unchanged: checked with callgrind on bench/bench_linalg).
 *  - Decisions (pivots, signs, rank, singularity tests, branch choices, convergence tests) look
 *    at real parts only: SC_RE(x), SC_MAG(x) = |Re x|. A decision must also be locally constant
 *    in the real problem: a test for an exact zero, which the real code may use as a shortcut,
 *    must in the complex build test both parts (C's == on complex numbers does), or the
 *    imaginary part of a perturbed entry is silently dropped.
 *  - |x| as a value is SC_ABS(x) = x or -x by the sign of the real part (analytic away from 0);
 *    norms used only as scales or in decisions are computed from real parts and are double.
 *    Never conj(): a Householder reflector with conjugation is not analytic, which is also why
 *    the complex path never calls LAPACK (zgeqrf conjugates) and always runs the native kernels.
 *  - Outputs that are decision quantities (rank, growth, residuals, condition estimates) stay
 *    double in both builds. Condition estimates are LAPACK's and exist only in the double build:
 *    the complex variants refuse a non-NULL rcond with AP_ERR_ARG (take it from the double
 *    routine at the real part).
 *  - Calls into libraries that only exist for double (LAPACK, BLAS) sit in static wrappers that
 *    the complex build replaces by stubs it never reaches (its size test is constant "native").
 *
 * Derivatives: seed x = x0 + i AP_CS_STEP dx, read SC_IM(f) / AP_CS_STEP. */
#ifndef AP_LINALG_SCALAR_H
#define AP_LINALG_SCALAR_H

#include <math.h>

/* Imaginary step of the complex-step method: small enough that products of two imaginary parts
 * (h^2 ~ 1e-200) vanish against O(1) values, large enough that an imaginary part times the
 * small factors of a mechanism (1e-100 at worst) stays a normal number. */
#define AP_CS_STEP 1e-100

#ifdef AP_SC_COMPLEX
#include <complex.h>
#undef I          /* C11 7.3.1: a program may undefine these; model code uses I as a name */
#undef complex
typedef double _Complex ap_sc;
#define AP_SC(name) name##_cs
#define SC_RE(x) creal(x)
#define SC_IM(x) cimag(x)
#define SC_MAG(x) fabs(creal(x))
#define SC_SQRT(x) csqrt(x)
#define SC_FINITE(x) (isfinite(creal(x)) && isfinite(cimag(x)))
#define SC_IM_FINITE(x) isfinite(cimag(x))
static inline ap_sc sc_abs_(ap_sc x) { return creal(x) < 0.0 ? -x : x; }
#define SC_ABS(x) sc_abs_(x)
#define SC_HYPOT(a, b) csqrt((a) * (a) + (b) * (b))
#define SC_COS(x) ccos(x)
#define SC_SIN(x) csin(x)
#else
typedef double ap_sc;
#define AP_SC(name) name
#define SC_RE(x) (x)
#define SC_IM(x) 0.0
#define SC_MAG(x) fabs(x)
#define SC_SQRT(x) sqrt(x)
#define SC_FINITE(x) isfinite(x)
#define SC_IM_FINITE(x) 1
#define SC_ABS(x) fabs(x)
#define SC_HYPOT(a, b) hypot((a), (b))
#define SC_COS(x) cos(x)
#define SC_SIN(x) sin(x)
#endif

#endif
