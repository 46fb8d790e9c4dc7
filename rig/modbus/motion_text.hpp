// Small pieces both table clients (rig-v1 map and CiA 402) use in their waits and messages:
// angle, code and duration formatting, and a trapezoidal move's duration for time bounds.
#pragma once
#include <cmath>
#include <cstdio>
#include <string>

namespace rig::modbus::detail {

inline std::string deg_str(double d) {
  char b[48];
  std::snprintf(b, sizeof b, "%.4f°", d);
  return b;
}

inline std::string hex4(unsigned v) {
  char b[16];
  std::snprintf(b, sizeof b, "0x%04X", v);
  return b;
}

inline std::string secs(double s) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f s", s);
  return b;
}

// Duration of a trapezoidal move of `dist` from rest to rest (peak velocity v, acceleration a).
inline double trapezoid_time(double dist, double v, double a) {
  if (v <= 0 || a <= 0) return 0;
  dist = std::fabs(dist);
  if (dist >= v * v / a) return dist / v + v / a;
  return 2.0 * std::sqrt(dist / a);
}

}  // namespace rig::modbus::detail
