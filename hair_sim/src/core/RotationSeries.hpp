#pragma once
/// Internal to the core: the small-angle series of the rotation helpers, for one double (Simulator.cpp's
/// rotationVectorBetween, rotateByVector and rotatePerpendicular) or for GCC vector lanes (StepLanes.cpp's
/// swing, rotationCosSin as rotatePerpendicular takes it): the same operations in the same order, so a lane
/// gives the bits of the scalar function.

namespace hair_sim {
namespace series {

#if defined(__GNUC__)
#define HAIR_SIM_SERIES_INLINE inline __attribute__((always_inline))
#else
#define HAIR_SIM_SERIES_INLINE inline
#endif

/// atan(x) / x for x^2 = x2 < 0.01, to x^16 (the first term left out, x^18 / 19, is below 6e-20).
template <class T>
HAIR_SIM_SERIES_INLINE T atanOverX(T x2) {
  T p = T{} + 1.0 / 17.0;
  p = p * x2 - 1.0 / 15.0;
  p = p * x2 + 1.0 / 13.0;
  p = p * x2 - 1.0 / 11.0;
  p = p * x2 + 1.0 / 9.0;
  p = p * x2 - 1.0 / 7.0;
  p = p * x2 + 1.0 / 5.0;
  p = p * x2 - 1.0 / 3.0;
  p = p * x2 + 1.0;
  return p;
}

/// For a rotation by the angle a, a2 = a^2 < 0.01: cos a and sin(a) / a, to a^10 (the terms left out are
/// below 2e-21). A rotation by a vector perpendicular to the vector it turns needs no more.
template <class T>
HAIR_SIM_SERIES_INLINE void rotationCosSin(T a2, T& cos_a, T& sin_a_over_a) {
  cos_a =
      1.0 + a2 * (-1.0 / 2.0 +
                  a2 * (1.0 / 24.0 + a2 * (-1.0 / 720.0 + a2 * (1.0 / 40320.0 + a2 * (-1.0 / 3628800.0)))));
  sin_a_over_a =
      1.0 + a2 * (-1.0 / 6.0 + a2 * (1.0 / 120.0 + a2 * (-1.0 / 5040.0 +
                                                         a2 * (1.0 / 362880.0 + a2 * (-1.0 / 39916800.0)))));
}

/// rotationCosSin and (1 - cos a) / a^2, to a^10 (no cancellation in 1 - cos).
template <class T>
HAIR_SIM_SERIES_INLINE void rotation(T a2, T& cos_a, T& sin_a_over_a, T& one_minus_cos_over_a2) {
  rotationCosSin(a2, cos_a, sin_a_over_a);
  one_minus_cos_over_a2 =
      0.5 +
      a2 * (-1.0 / 24.0 +
            a2 * (1.0 / 720.0 + a2 * (-1.0 / 40320.0 + a2 * (1.0 / 3628800.0 + a2 * (-1.0 / 479001600.0)))));
}

}  // namespace series
}  // namespace hair_sim
