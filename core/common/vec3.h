#pragma once

#include <cmath>

#include "core/common/cpu_gpu.h"

namespace fenestra {

// A 3-vector of T (double on the host, float in traversal), usable on CPU and GPU.
template <typename T>
struct Vec3T {
  T x, y, z;

  FENESTRA_CPU_GPU T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  FENESTRA_CPU_GPU Vec3T operator+(Vec3T o) const { return {x + o.x, y + o.y, z + o.z}; }
  FENESTRA_CPU_GPU Vec3T operator-(Vec3T o) const { return {x - o.x, y - o.y, z - o.z}; }
  FENESTRA_CPU_GPU Vec3T operator-() const { return {-x, -y, -z}; }
  FENESTRA_CPU_GPU Vec3T operator*(T s) const { return {x * s, y * s, z * s}; }
  FENESTRA_CPU_GPU Vec3T operator/(T s) const { return {x / s, y / s, z / s}; }
  FENESTRA_CPU_GPU Vec3T& operator+=(Vec3T o) {
    x += o.x;
    y += o.y;
    z += o.z;
    return *this;
  }
};

template <typename T>
FENESTRA_CPU_GPU inline Vec3T<T> operator*(T s, Vec3T<T> v) {
  return v * s;
}
template <typename T>
FENESTRA_CPU_GPU inline T Dot(Vec3T<T> a, Vec3T<T> b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <typename T>
FENESTRA_CPU_GPU inline Vec3T<T> Cross(Vec3T<T> a, Vec3T<T> b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename T>
FENESTRA_CPU_GPU inline T Length(Vec3T<T> v) {
  return sqrt(Dot(v, v));
}
template <typename T>
FENESTRA_CPU_GPU inline Vec3T<T> Normalize(Vec3T<T> v) {
  return v / Length(v);
}

using Vec3d = Vec3T<double>;
using Vec3f = Vec3T<float>;

}  // namespace fenestra
