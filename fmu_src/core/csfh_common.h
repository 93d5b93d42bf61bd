/* Small shared helpers of the physics core. */
#ifndef CSFH_COMMON_H
#define CSFH_COMMON_H

#define CSFH_PI 3.14159265358979323846

/* 2-D scalar cross product a x b = a_x b_y - a_y b_x (= a^T 1bar b of the paper). */
static inline double csfh_cross2(const double a[2], const double b[2])
{
    return a[0] * b[1] - a[1] * b[0];
}

/* Saturating evaluation counter. */
static inline void csfh_count(int *counter)
{
    if (*counter < 0x7fffffff) {
        (*counter)++;
    }
}

#endif
