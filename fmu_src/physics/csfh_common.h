/* Small shared helpers of the physics core. */
#ifndef CSFH_COMMON_H
#define CSFH_COMMON_H

#include <float.h>
#include <math.h>

#define CSFH_PI 3.14159265358979323846

/* 2-D scalar cross product a x b = a_x b_y - a_y b_x (= a^T 1bar b of the paper). */
static inline double csfh_cross2(const double a[2], const double b[2])
{
    return a[0] * b[1] - a[1] * b[0];
}

/* |(x, y)|: sqrt(x^2 + y^2), within an ulp of hypot and several times cheaper; hypot itself
 * where the squares would overflow or underflow (|x|, |y| beyond ~1e154 or below ~1e-154). */
static inline double csfh_norm2(double x, double y)
{
    const double s = x * x + y * y;
    if (s < DBL_MAX && s > DBL_MIN) {
        return sqrt(s);
    }
    return hypot(x, y);
}

/* x^n for x > 0: x sqrt(x) for n = 1.5 (the Hertz exponent, a few ulp from pow and several
 * times cheaper), x for n = 1, pow otherwise. */
static inline double csfh_pow_n(double x, double n)
{
    if (n == 1.5) {
        return x * sqrt(x);
    }
    if (n == 1.0) {
        return x;
    }
    return pow(x, n);
}

/* Saturating evaluation counter. */
static inline void csfh_count(int *counter)
{
    if (*counter < 0x7fffffff) {
        (*counter)++;
    }
}

#endif
