#include "core/trace/sky_horizon.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace fenestra {
namespace {

struct Point2 {
  double x, y;
};

double Cross(Point2 a, Point2 b) { return a.x * b.y - a.y * b.x; }

// The part of `polygon` on the left of the line through the origin along `edge` (or on it).
std::vector<Point2> ClipLeft(const std::vector<Point2>& polygon, Point2 edge) {
  std::vector<Point2> out;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Point2 a = polygon[i], b = polygon[(i + 1) % polygon.size()];
    const double da = Cross(edge, a), db = Cross(edge, b);
    if (da >= 0) out.push_back(a);
    if ((da >= 0) != (db >= 0)) {
      const double t = da / (da - db);
      out.push_back({a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)});
    }
  }
  return out;
}

// Least distance from the origin to a convex polygon (0 when it holds the origin).
double Distance(const std::vector<Point2>& polygon) {
  bool inside = true;
  double best = INFINITY;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Point2 a = polygon[i], b = polygon[(i + 1) % polygon.size()];
    const Point2 ab{b.x - a.x, b.y - a.y};
    if (Cross(ab, {-a.x, -a.y}) < 0) inside = false;
    const double length2 = ab.x * ab.x + ab.y * ab.y;
    const double t =
        length2 > 0 ? std::clamp(-(a.x * ab.x + a.y * ab.y) / length2, 0.0, 1.0) : 0.0;
    best = std::min(best, std::hypot(a.x + t * ab.x, a.y + t * ab.y));
  }
  return inside && polygon.size() >= 3 ? 0.0 : best;
}

struct Box {
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  void Add(Vec3f p) {
    const double v[3] = {p.x, p.y, p.z};
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], v[k]), hi[k] = std::max(hi[k], v[k]);
  }
};

}  // namespace

std::vector<float> SkyHorizon(const TraceGeometry& geometry, const TraceWindow& window) {
  // Room for float rounding of the ray's origin and direction [m, and sine]
  constexpr double kMargin = 1e-3, kSineMargin = 1e-4;
  const int bins = kHorizonAzimuthBins;
  std::vector<float> horizon(static_cast<size_t>(window.Parts()) * bins, -1.0f);
  const double wedge = 2 * std::numbers::pi / bins;
  for (int part = 0; part < window.Parts(); ++part) {
    Box p;
    for (const float u0 : {0.0f, 1.0f}) {
      for (const float u1 : {0.0f, 1.0f}) p.Add(window.PartPoint(part, u0, u1));
    }
    for (size_t t = 0; t < geometry.TriangleCount(); ++t) {
      if (!HasArea(geometry, t)) continue;
      Box b;
      for (int k = 0; k < 3; ++k) b.Add(geometry.vertices[3 * t + k]);
      // The vectors from the part to the triangle: the box b - p, widened by the margin
      const double z_max = b.hi[2] - p.lo[2] + kMargin;
      const double x0 = b.lo[0] - p.hi[0] - kMargin, x1 = b.hi[0] - p.lo[0] + kMargin;
      const double y0 = b.lo[1] - p.hi[1] - kMargin, y1 = b.hi[1] - p.lo[1] + kMargin;
      const std::vector<Point2> footprint = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
      for (int a = 0; a < bins; ++a) {
        const double from = -std::numbers::pi + a * wedge, to = from + wedge;
        const std::vector<Point2> clipped =
            ClipLeft(ClipLeft(footprint, {std::cos(from), std::sin(from)}),
                     {-std::cos(to), -std::sin(to)});
        if (clipped.size() < 3) continue;
        const double r = Distance(clipped);
        const double sine = z_max <= 0 ? 0.0 : (r > 0 ? z_max / std::hypot(r, z_max) : 1.0);
        float& h = horizon[static_cast<size_t>(part) * bins + a];
        h = std::max(h, static_cast<float>(std::min(1.0, sine + kSineMargin)));
      }
    }
  }
  // A direction near a bin's edge may round into the next bin: each bin also takes its
  // neighbours' bounds
  std::vector<float> widened = horizon;
  for (int part = 0; part < window.Parts(); ++part) {
    const float* h = &horizon[static_cast<size_t>(part) * bins];
    for (int a = 0; a < bins; ++a) {
      widened[static_cast<size_t>(part) * bins + a] =
          std::max({h[(a + bins - 1) % bins], h[a], h[(a + 1) % bins]});
    }
  }
  return widened;
}

}  // namespace fenestra
