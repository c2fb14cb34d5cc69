#pragma once
// One angle convention for the whole project: radians, counter-clockwise positive about Up,
// headings measured from East. Wrapped angles lie in [-pi, pi).
#include <cmath>

namespace driftcorr {

constexpr double kPi = 3.14159265358979323846;

inline double DegToRad(double deg) { return deg * kPi / 180.0; }
inline double RadToDeg(double rad) { return rad * 180.0 / kPi; }

/// Wraps an angle into [-pi, pi).
inline double WrapAngle(double rad) {
    double wrapped = std::fmod(rad + kPi, 2.0 * kPi);
    if (wrapped < 0.0) wrapped += 2.0 * kPi;
    return wrapped - kPi;
}

/// Shortest signed difference a - b, in [-pi, pi).
inline double AngleDiff(double a_rad, double b_rad) { return WrapAngle(a_rad - b_rad); }

}  // namespace driftcorr
