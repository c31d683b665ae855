/* Internal to the refsys*.c files: the composite Gauss-Legendre quadrature of the closed forms
 * (the sleigh's x, y; the turntable's position with Omega(t)). A panel spans at most half a
 * radian of the fastest rotation in the integrand and at most half a second; RS_GL_N points a
 * panel (rs_gauss_legendre of refsys.h gives the nodes and weights on [-1, 1]). */
#ifndef AP_TESTS_REFSYS_QUAD_H
#define AP_TESTS_REFSYS_QUAD_H

#define RS_GL_N 16

/* Number of panels for an interval of length |t| whose integrand turns at most at `rate`. */
int rs_panels(double t, double rate);

#endif
