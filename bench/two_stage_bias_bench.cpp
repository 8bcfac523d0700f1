// Where the two-stage method's bias comes from (bench/README.md, "Two-stage bias"): the
// city office at one blind design, its indoor paths traced once, and every light
// contribution they score at the window (x_w, omega, window cell, value) also carried on
// into the outdoor scene by one outdoor path from x_w along omega. That continuation is a
// one-stage estimate with the same indoor paths, so the difference between it and
// value x O[cell] is the two-stage error alone, without the indoor noise, per window part
// and direction cell. Two ways of using the cells are compared:
//   cells: every contribution through O (the textbook split: O averages the sky and the
//          buildings over each cell);
//   split: contributions whose view reaches the sky scored directly by sky bin, the rest
//          through O of the reflected light (what core/trace/two_stage_modes.h does).
// and two direction densities of the outdoor paths within a cell (solid angle, projected
// solid angle). Usage:
//   two_stage_bias_bench [--design ALPHA,W,S,T] [--black-city] [--cells 288|1152]
//                        [--parts CxR] [--indoor-paths N] [--outdoor-paths N] [--top K]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numeric>
#include <string>
#include <vector>

#include "bench/bench_util.h"
#include "core/dc/backend_support.h"
#include "core/dc/two_stage.h"
#include "core/trace/embree_scene.h"
#include "core/trace/two_stage_cpu.h"

namespace fenestra {
namespace {

constexpr int kBatches = 8;
constexpr int kSkyBins = kTregenzaBinCount;
constexpr uint32_t kContinuationStream = 0x40000000u;

struct Args {
  double alpha = 0.0, width = 0.13, spacing = 0.07, thickness = 0.014;
  bool black_city = false;
  int cells = 288;
  WindowParts parts{0, 0};  // 0 = automatic
  int64_t indoor_paths = 1'000'000;
  int64_t outdoor_paths = 20'000'000;
  int top = 12;
};

Args Parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto next = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (arg == "--design") {
      std::sscanf(next().c_str(), "%lf,%lf,%lf,%lf", &a.alpha, &a.width, &a.spacing, &a.thickness);
    } else if (arg == "--black-city") {
      a.black_city = true;
    } else if (arg == "--cells") {
      a.cells = std::atoi(next().c_str());
    } else if (arg == "--parts") {
      a.parts = ValueOrExit(ParseWindowParts(next()));
    } else if (arg == "--indoor-paths") {
      a.indoor_paths = std::atoll(next().c_str());
    } else if (arg == "--outdoor-paths") {
      a.outdoor_paths = std::atoll(next().c_str());
    } else if (arg == "--top") {
      a.top = std::atoi(next().c_str());
    } else {
      std::fprintf(stderr, "unknown argument %s\n", arg.c_str());
      std::exit(2);
    }
  }
  return a;
}

// Outdoor sums per window cell, for both uses of the cells: the reflected light by bin,
// the first segments that reached the sky by bin, and per-path second moments of the sky
// sums (a path scores one bin).
struct OutdoorSums {
  int cells = 0;
  uint64_t paths = 0;
  std::vector<double> reflected, first;   // cells x 146
  std::vector<double> first_count;        // cells
  std::vector<double> reflected_squares;  // cells: sum over paths of (sky score)^2, reflected
  std::vector<double> all_squares;        // cells: the same, every path

  double Sky(const std::vector<double>& v, int c) const {
    return std::accumulate(v.begin() + c * kSkyBins + 1, v.begin() + (c + 1) * kSkyBins, 0.0);
  }
};

// OutdoorMode's paths with the first escapes' bins seen, and a choice of direction density.
template <class Sink>
struct ObservedOutdoorMode : OutdoorMode<Sink> {
  bool projected;
  template <class Intersector>
  PathState Start(const Intersector& scene, const PathRandom& random) const {
    PathState state = OutdoorMode<Sink>::Start(scene, random);
    if (!projected) {
      const Uniform4 u = random.Draw(0, 0);
      const int part = this->cell / this->basis->cell_count;
      state.direction = this->window.ToWorld(SampleBasisCell(
          *this->basis, this->cell - part * this->basis->cell_count, u.u[2], u.u[3], false));
    }
    return state;
  }
  void Escape(const PathState& path) {
    if (path.vertex == 0) this->sink->first_bin = TregenzaBin(path.direction);
    OutdoorMode<Sink>::Escape(path);
  }
};

OutdoorSums TraceOutdoor(const EmbreeIntersector& scene, const TraceGeometry& geometry,
                         const TraceWindow& window, const HemisphereBasis& basis,
                         uint64_t paths_per_cell, bool projected) {
  struct Slot {
    double reflected[kSkyBins] = {}, first[kSkyBins] = {};
    double first_count = 0, reflected_squares = 0, all_squares = 0;
    int first_bin = -1;
    void Add(int bin, double value) {
      reflected[bin] += value;
      if (bin > 0) reflected_squares += value * value, all_squares += value * value;
    }
    void AddFirstEscape() {
      first[first_bin] += 1;
      first_count += 1;
      if (first_bin > 0) all_squares += 1;
    }
  };
  PathSettings settings{-1, true, 1.0f, 1u << 20};
  OutdoorSums sums;
  sums.cells = WindowCellCount(window, basis);
  sums.paths = paths_per_cell;
  sums.reflected.assign(sums.cells * kSkyBins, 0.0);
  sums.first.assign(sums.cells * kSkyBins, 0.0);
  sums.first_count.assign(sums.cells, 0.0);
  sums.reflected_squares.assign(sums.cells, 0.0);
  sums.all_squares.assign(sums.cells, 0.0);
  TraceChunksCpu<Slot>(
      sums.cells, 0,
      [&](uint64_t c, Slot& slot) {
        ObservedOutdoorMode<Slot> mode{{window, TraceWindows{&window, 1, sums.cells, window.Area()},
                                        &basis, static_cast<int>(c), &slot},
                                       projected};
        for (uint64_t p = 0; p < paths_per_cell; ++p) {
          TracePath(scene, geometry.Surfaces(), settings,
                    PathRandom(1, kOutdoorStreamBase + static_cast<uint32_t>(c), p), mode);
        }
      },
      [&](uint64_t c, const Slot& slot) {
        for (int j = 0; j < kSkyBins; ++j) {
          sums.reflected[c * kSkyBins + j] = slot.reflected[j];
          sums.first[c * kSkyBins + j] = slot.first[j];
        }
        sums.first_count[c] = slot.first_count;
        sums.reflected_squares[c] = slot.reflected_squares;
        sums.all_squares[c] = slot.all_squares;
      });
  return sums;
}

// The outdoor view, scoring everything into its window cell but remembering for the sink
// where the score arrives and whether its view reaches the sky.
struct WatchingOutdoor {
  OutdoorView<EmbreeIntersector> view;
  mutable Vec3f point{}, omega{};
  mutable bool escapes = false;
  template <class Sink>
  void Score(const TraceWindow& window, int, Vec3f p, Vec3f o, int cell, double value, bool,
             Sink* sink) const {
    point = p, omega = o, escapes = view.Escapes(p, window.normal, o);
    sink->Add(cell, value);
  }
};

// An outdoor path from a given window point and direction.
struct ContinuationMode {
  Vec3f origin, direction;
  TraceWindow window;  // outdoor frame
  double sky = 0;      // its score in the sky bins
  double* bins;        // weight by bin
  template <class Intersector>
  PathState Start(const Intersector&, const PathRandom&) const {
    return PathState{origin, direction, 1.0f, 0, 0};
  }
  template <class Intersector>
  void AtReflection(const Intersector&, const PathState&, const ReflectionVertex&,
                    const PathRandom&) const {}
  void Escape(const PathState& path) {
    if (window.Crosses(path.origin, path.direction)) return;
    const int bin = TregenzaBin(path.direction);
    bins[bin] += path.weight;
    if (bin > 0) sky += path.weight;
  }
  void Finish(const PathStats&) const {}
};

// Per (batch, sensor): what the indoor paths scored, by window cell and by sky bin.
struct Tally {
  std::vector<double> all, met;  // per window cell: every score; scores whose view met a surface
  std::vector<double> exact;     // per window cell: score x the continuation's sky sum
  std::vector<double> exact_direct;   // per window cell: the part of `exact` that saw the sky
  double exact_bins[kSkyBins] = {};   // score x continuation, by bin
  double direct_bins[kSkyBins] = {};  // scores whose view reached the sky, by bin
};

struct IndoorContext {
  const WatchingOutdoor* outdoor;
  const EmbreeIntersector* outdoor_scene;
  SurfaceTable outdoor_surfaces;
  TraceWindow outdoor_window;
  const HemisphereBasis* basis;
  int window_cells;
};

struct IndoorSink {
  Tally* tally;
  const IndoorContext* context;
  uint32_t stream;
  uint64_t* continuations;
  void Add(int cell, double value) {
    const WatchingOutdoor& w = *context->outdoor;
    tally->all[cell] += value;
    if (w.escapes) {
      const int bin = TregenzaBin(w.omega);
      tally->direct_bins[bin] += value;
      tally->exact_bins[bin] += value;
      if (bin > 0) tally->exact[cell] += value, tally->exact_direct[cell] += value;
      return;
    }
    tally->met[cell] += value;
    double bins[kSkyBins] = {};
    ContinuationMode mode{OffsetRayOrigin(w.point + w.view.offset, context->outdoor_window.normal),
                          w.omega, context->outdoor_window, 0.0, bins};
    const PathSettings settings{-1, true, 1.0f, 1u << 20};
    TracePath<EmbreeIntersector, ContinuationMode, 0>(
        *context->outdoor_scene, context->outdoor_surfaces, settings,
        PathRandom(2, kContinuationStream + stream, (*continuations)++), mode);
    tally->exact[cell] += value * mode.sky;
    for (int j = 0; j < kSkyBins; ++j) tally->exact_bins[j] += value * bins[j];
  }
};

double Mean(const std::vector<double>& v) {
  return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

double StandardErrorOfMean(const std::vector<double>& v) {
  const double m = Mean(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / (v.size() * (v.size() - 1.0)));
}

// World elevation and azimuth (from north, clockwise) of a cell's centre [deg].
void CellDirection(const HemisphereBasis& basis, const Window& window, int cell, double* elevation,
                   double* azimuth) {
  const Vec3d d = BasisCellCenter(basis, cell);
  const Vec3d w = window.across * d.x + window.up * d.y + window.normal * d.z;
  *elevation = std::asin(std::clamp(w.z, -1.0, 1.0)) * 180 / kPi;
  *azimuth = std::fmod(std::atan2(w.x, w.y) * 180 / kPi + 360, 360);
}

int Ring(const HemisphereBasis& basis, int cell) {
  int ring = 0;
  while (basis.cumulative[ring] <= cell) ++ring;
  return ring;
}

// The city office's scene, with the city's reflectance 0 for --black-city.
Scene LoadCityOffice(bool black_city) {
  Scene scene =
      ValueOrExit(LoadScene(std::string(FENESTRA_SOURCE_DIR) + "/examples/city_office/scene.json"));
  if (black_city) {
    for (Material& m : scene.materials) {
      if (m.name == "city") m.reflectance = 0;
    }
  }
  return scene;
}

// Traces the indoor paths of every sensor in kBatches batches, every score continued
// outdoors, and prints their count; the tallies per (sensor, batch), sensor-major.
std::vector<Tally> TraceIndoor(const Scene& scene, const BlindDesign& design,
                               const WindowParts& parts, const HemisphereBasis& basis,
                               const TraceGeometry& outdoor, EmbreeIntersector outdoor_scene,
                               const TraceWindow& outdoor_window, int cells, int64_t indoor_paths) {
  const TriangleMesh room = SelectSide(AssembleMesh(scene, design), Side::kIndoor);
  const TraceGeometry indoor = ValueOrExit(PrepareTraceGeometry(room, scene.materials));
  const auto indoor_scene = ValueOrExit(EmbreeScene::Build(indoor));
  const std::vector<TraceSensor> sensors = LocalSensors(indoor, scene.sensors);
  const TraceWindow window = LocalWindow(indoor, scene.window(), parts);
  const WatchingOutdoor prototype{{outdoor_scene, OutdoorOffset(indoor, outdoor), nullptr}};
  const int sensor_count = static_cast<int>(sensors.size());
  const PathSettings settings{-1, true, 1.0f, 1u << 20};
  const uint64_t paths = static_cast<uint64_t>(indoor_paths);
  struct Slot {
    Tally tally;
    uint64_t continuations = 0;
  };
  std::vector<Tally> tallies(kBatches * sensor_count);
  uint64_t continuations = 0;
  TraceChunksCpu<Slot>(
      kBatches * sensor_count, 0,
      [&](uint64_t c, Slot& slot) {
        const int s = static_cast<int>(c / kBatches), b = static_cast<int>(c % kBatches);
        Tally& t = slot.tally;
        t.all.assign(cells, 0.0), t.met.assign(cells, 0.0);
        t.exact.assign(cells, 0.0), t.exact_direct.assign(cells, 0.0);
        WatchingOutdoor watcher = prototype;
        const IndoorContext context{
            &watcher, &prototype.view.scene, outdoor.Surfaces(), outdoor_window, &basis, cells};
        IndoorSink sink{&t, &context, static_cast<uint32_t>(s), &slot.continuations};
        slot.continuations = BatchStart(paths, kBatches, b) * 64;
        IndoorMode<IndoorSink, WatchingOutdoor> mode{
            sensors[s].position,
            sensors[s].normal,
            TraceWindows{&window, 1, WindowCellCount(window, basis), window.Area()},
            &basis,
            -1,
            &watcher,
            &sink};
        for (uint64_t p = BatchStart(paths, kBatches, b); p < BatchStart(paths, kBatches, b + 1);
             ++p) {
          TracePath<EmbreeIntersector, decltype(mode), 0>(
              indoor_scene->Intersector(), indoor.Surfaces(), settings,
              PathRandom(3, static_cast<uint32_t>(s), p), mode);
        }
      },
      [&](uint64_t c, const Slot& slot) {
        tallies[c] = slot.tally;
        continuations += slot.continuations - BatchStart(paths, kBatches, c % kBatches) * 64;
      });
  std::printf("indoor: %d sensors x %lld paths in %d batches, %llu outdoor continuations\n\n",
              sensor_count, static_cast<long long>(indoor_paths), kBatches,
              static_cast<unsigned long long>(continuations));
  return tallies;
}

// One sensor's sky sums per batch (one-stage; two-stage through the cells with either
// density; split; the bias through the cells of the direct and the reflected light) and
// the sky-bin distributions of one-stage, cells and split, averaged over the batches.
struct SensorBatches {
  std::vector<double> exact, old_projected, old_solid, split, direct_bias, reflected_bias;
  std::vector<double> d_exact, d_old, d_split;
};

// Sums sensor s's tallies against the outdoor sums, batch by batch.
SensorBatches SumSensorBatches(const std::vector<Tally>& tallies, int s,
                               const OutdoorSums& projected, const OutdoorSums& solid,
                               uint64_t paths) {
  const int cells = projected.cells;
  const double n = static_cast<double>(projected.paths);
  const double inv_paths = kBatches / static_cast<double>(paths);  // per batch
  SensorBatches r;
  r.d_exact.assign(kSkyBins, 0.0), r.d_old.assign(kSkyBins, 0.0), r.d_split.assign(kSkyBins, 0.0);
  for (int b = 0; b < kBatches; ++b) {
    const Tally& t = tallies[s * kBatches + b];
    double e = 0, op = 0, os = 0, sp = 0, db = 0, rb = 0;
    for (int j = 1; j < kSkyBins; ++j) sp += t.direct_bins[j];
    for (int c = 0; c < cells; ++c) {
      e += t.exact[c];
      const double first = projected.Sky(projected.first, c) / n;
      const double reflected = projected.Sky(projected.reflected, c) / n;
      op += t.all[c] * (first + reflected);
      os += t.all[c] * (solid.Sky(solid.first, c) + solid.Sky(solid.reflected, c)) / n;
      const double met = n - projected.first_count[c];
      if (met > 0) sp += t.met[c] * projected.Sky(projected.reflected, c) / met;
      db += t.all[c] * first - t.exact_direct[c];
      rb += t.all[c] * reflected - (t.exact[c] - t.exact_direct[c]);
    }
    for (int j = 0; j < kSkyBins; ++j) {
      r.d_exact[j] += t.exact_bins[j] * inv_paths / kBatches;
      r.d_split[j] += t.direct_bins[j] * inv_paths / kBatches;
      for (int c = 0; c < cells; ++c) {
        const double met = n - projected.first_count[c];
        r.d_old[j] += t.all[c] *
                      (projected.first[c * kSkyBins + j] + projected.reflected[c * kSkyBins + j]) /
                      n * inv_paths / kBatches;
        if (met > 0) {
          r.d_split[j] +=
              t.met[c] * projected.reflected[c * kSkyBins + j] / met * inv_paths / kBatches;
        }
      }
    }
    r.exact.push_back(e * inv_paths), r.old_projected.push_back(op * inv_paths);
    r.old_solid.push_back(os * inv_paths), r.split.push_back(sp * inv_paths);
    r.direct_bias.push_back(db * inv_paths), r.reflected_bias.push_back(rb * inv_paths);
  }
  return r;
}

// O's noise in sensor s's two-stage sky sum, through the cells and split: per cell, the
// variance of its sky row sum times the cell's weight squared.
std::pair<double, double> OutdoorVariances(const std::vector<Tally>& tallies, int s,
                                           const OutdoorSums& projected, uint64_t paths) {
  const int cells = projected.cells;
  const double n = static_cast<double>(projected.paths);
  const double inv_paths = kBatches / static_cast<double>(paths);  // per batch
  double old_var = 0, split_var = 0;
  for (int c = 0; c < cells; ++c) {
    double all = 0, met_weight = 0;
    for (int b = 0; b < kBatches; ++b) {
      all += tallies[s * kBatches + b].all[c] * inv_paths / kBatches;
      met_weight += tallies[s * kBatches + b].met[c] * inv_paths / kBatches;
    }
    const double mean =
        (projected.Sky(projected.first, c) + projected.Sky(projected.reflected, c)) / n;
    old_var += all * all * std::max(0.0, projected.all_squares[c] / n - mean * mean) / n;
    const double met = n - projected.first_count[c];
    if (met > 1) {
      const double m = projected.Sky(projected.reflected, c) / met;
      split_var += met_weight * met_weight *
                   std::max(0.0, projected.reflected_squares[c] / met - m * m) / met;
    }
  }
  return {old_var, split_var};
}

// Prints sensor s's row: the one-stage sky sum, each two-stage sum's difference from it in
// % and in standard errors, the bias's direct and reflected parts, and the L1 distances of
// the sky-bin distributions.
void PrintSensorRow(int s, const SensorBatches& r, double old_var, double split_var) {
  auto difference = [&](const std::vector<double>& two, double outdoor_var) {
    std::vector<double> d(kBatches);
    for (int b = 0; b < kBatches; ++b) d[b] = two[b] - r.exact[b];
    const double se = std::sqrt(std::pow(StandardErrorOfMean(d), 2) + outdoor_var);
    return std::pair{Mean(d), se};
  };
  const double one = Mean(r.exact);
  const auto [dp, sep] = difference(r.old_projected, old_var);
  const auto [dsplit, sesplit] = difference(r.split, split_var);
  const auto [dsolid, sesolid] = difference(r.old_solid, old_var);
  double l1_old = 0, l1_split = 0, total = 0;
  for (int j = 0; j < kSkyBins; ++j) {
    l1_old += std::abs(r.d_old[j] - r.d_exact[j]);
    l1_split += std::abs(r.d_split[j] - r.d_exact[j]);
    total += r.d_exact[j];
  }
  std::printf(
      "S%-5d %.4e ± %.1e    %+6.2f%% (%+5.1f SE)            %+6.2f%% (%+5.1f SE)            "
      "%+6.2f%% (%+5.1f SE)    %+6.2f%% %+6.2f%%; %5.1f%% / %5.1f%%\n",
      s + 1, one, StandardErrorOfMean(r.exact), 100 * dp / one, dp / sep, 100 * dsplit / one,
      dsplit / sesplit, 100 * dsolid / one, dsolid / sesolid, 100 * Mean(r.direct_bias) / one,
      100 * Mean(r.reflected_bias) / one, 100 * l1_old / total, 100 * l1_split / total);
}

// Per sensor: one-stage with the same paths against both uses of the cells.
void PrintSensorSums(const std::vector<Tally>& tallies, const OutdoorSums& projected,
                     const OutdoorSums& solid, uint64_t paths) {
  std::printf(
      "sky sums [sr] per sensor: one-stage with the same indoor paths (exact outdoors), two-stage "
      "through the cells and split; differences relative to the one-stage value, in standard "
      "errors of the difference (indoor paths in 8 batches, and O's per-path moments)\n");
  std::printf("%-6s %-22s %-30s %-30s %-22s %s\n", "sensor", "one-stage", "cells (projected O)",
              "split (projected O)", "cells (solid-angle O)",
              "cells bias: direct + reflected; L1 cells / split");
  const int sensor_count = static_cast<int>(tallies.size()) / kBatches;
  for (int s = 0; s < sensor_count; ++s) {
    const SensorBatches r = SumSensorBatches(tallies, s, projected, solid, paths);
    const auto [old_var, split_var] = OutdoorVariances(tallies, s, projected, paths);
    PrintSensorRow(s, r, old_var, split_var);
  }
}

// One sensor's scores per window cell over all its paths (every score, those whose view
// met a surface, score x continuation and its direct part), its one-stage sky sum, and the
// bias of the two-stage sum per cell through the cells and split.
struct SensorCells {
  std::vector<double> all, met, exact, direct;
  double one = 0;
  std::vector<double> old_bias, split_bias;
};

// Sums sensor s's tallies over its batches and sets each window cell's bias against them.
SensorCells SumSensorCells(const std::vector<Tally>& tallies, int s, const OutdoorSums& projected,
                           uint64_t paths) {
  const int cells = projected.cells;
  const double n = static_cast<double>(projected.paths);
  SensorCells r;
  r.all.assign(cells, 0.0), r.met.assign(cells, 0.0);
  r.exact.assign(cells, 0.0), r.direct.assign(cells, 0.0);
  for (int b = 0; b < kBatches; ++b) {
    const Tally& t = tallies[s * kBatches + b];
    for (int c = 0; c < cells; ++c) {
      r.all[c] += t.all[c] / paths, r.met[c] += t.met[c] / paths;
      r.exact[c] += t.exact[c] / paths, r.direct[c] += t.exact_direct[c] / paths;
    }
  }
  r.one = std::accumulate(r.exact.begin(), r.exact.end(), 0.0);
  r.old_bias.resize(cells), r.split_bias.resize(cells);
  for (int c = 0; c < cells; ++c) {
    r.old_bias[c] =
        r.all[c] * (projected.Sky(projected.first, c) + projected.Sky(projected.reflected, c)) / n -
        r.exact[c];
    const double m = n - projected.first_count[c];
    r.split_bias[c] = r.direct[c] +
                      (m > 0 ? r.met[c] * projected.Sky(projected.reflected, c) / m : 0.0) -
                      r.exact[c];
  }
  return r;
}

// Prints the `top` window cells with the largest bias through the cells of sensor s (where
// they look, their share of the one-stage sum, how much of their view reaches the sky, both
// biases), then the biases summed over all cells.
void PrintLargestCellBiases(int s, const SensorCells& r, const OutdoorSums& projected,
                            const OutdoorSums& solid, const HemisphereBasis& basis,
                            const Window& world_window, const WindowParts& parts, int top) {
  const int cells = projected.cells;
  const double n = static_cast<double>(projected.paths);
  const double one = r.one;
  std::vector<int> order(cells);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return std::abs(r.old_bias[a]) > std::abs(r.old_bias[b]); });
  std::printf(
      "\nS%d: the %d window cells with the largest bias through the cells (of the sensor's "
      "one-stage sky sum %.4e); sky view = share of the cell's score (indoor) or paths "
      "(outdoor, projected / solid angle) whose view reaches the sky\n",
      s + 1, top, one);
  std::printf("%-5s %-5s %-4s %-13s %-8s %-22s %-9s %-9s\n", "part", "cell", "ring",
              "elev/azim deg", "share", "sky view in/out/solid", "cells", "split");
  double shown = 0, total_abs = 0;
  for (int c = 0; c < cells; ++c) total_abs += std::abs(r.old_bias[c]);
  for (int k = 0; k < std::min(top, cells); ++k) {
    const int c = order[k];
    const int part = c / basis.cell_count, dir = c % basis.cell_count;
    double elevation, azimuth;
    CellDirection(basis, world_window, dir, &elevation, &azimuth);
    shown += std::abs(r.old_bias[c]);
    std::printf(
        "%d,%d   %-5d %-4d %5.1f/%5.1f   %5.2f%%   %4.2f / %4.2f / %4.2f     %+6.2f%%  "
        "%+6.2f%%\n",
        part % parts.columns, part / parts.columns, dir, Ring(basis, dir), elevation, azimuth,
        100 * r.exact[c] / one, r.all[c] > 0 ? (r.all[c] - r.met[c]) / r.all[c] : 0.0,
        projected.first_count[c] / n, solid.first_count[c] / n, 100 * r.old_bias[c] / one,
        100 * r.split_bias[c] / one);
  }
  double old_sum = std::accumulate(r.old_bias.begin(), r.old_bias.end(), 0.0);
  double split_sum = std::accumulate(r.split_bias.begin(), r.split_bias.end(), 0.0);
  std::printf(
      "all cells: cells %+.2f%%, split %+.2f%% (sum of |bias| through the cells %.1f%%, of "
      "which the cells above %.1f%%)\n",
      100 * old_sum / one, 100 * split_sum / one, 100 * total_abs / one, 100 * shown / one);
}

}  // namespace
}  // namespace fenestra

int main(int argc, char** argv) {
  using namespace fenestra;
  const Args args = Parse(argc, argv);
  const Scene scene = LoadCityOffice(args.black_city);
  const BlindDesign design =
      ValueOrExit(DesignWithOverrides(scene, {{"alpha", args.alpha},
                                              {"width", args.width},
                                              {"spacing", args.spacing},
                                              {"thickness", args.thickness}}));
  const WindowParts parts =
      args.parts.columns > 0 ? args.parts : AutomaticWindowParts(scene.window());
  const HemisphereBasis basis = ValueOrExit(BasisFor(args.cells));
  std::printf(
      "city office, design alpha=%.3f w=%.3f s=%.3f t=%.3f, city reflectance %s, %d direction "
      "cells x %dx%d window parts, bounces unlimited (roulette) in both stages\n",
      args.alpha, args.width, args.spacing, args.thickness, args.black_city ? "0" : "0.2",
      basis.cell_count, parts.columns, parts.rows);

  // The outdoor stage, both direction densities
  const TraceGeometry outdoor = ValueOrExit(OutdoorGeometry(scene));
  const auto outdoor_scene = ValueOrExit(EmbreeScene::Build(outdoor));
  const TraceWindow outdoor_window = LocalWindow(outdoor, scene.window(), parts);
  const int cells = WindowCellCount(outdoor_window, basis);
  const uint64_t per_cell = static_cast<uint64_t>(args.outdoor_paths / cells);
  const OutdoorSums projected =
      TraceOutdoor(outdoor_scene->Intersector(), outdoor, outdoor_window, basis, per_cell, true);
  const OutdoorSums solid =
      TraceOutdoor(outdoor_scene->Intersector(), outdoor, outdoor_window, basis, per_cell, false);
  std::printf("outdoor: %llu paths per window cell (%d cells), each density\n",
              static_cast<unsigned long long>(per_cell), cells);

  // The indoor paths, every score continued outdoors
  const std::vector<Tally> tallies =
      TraceIndoor(scene, design, parts, basis, outdoor, outdoor_scene->Intersector(),
                  outdoor_window, cells, args.indoor_paths);
  const uint64_t paths = static_cast<uint64_t>(args.indoor_paths);
  PrintSensorSums(tallies, projected, solid, paths);

  // The cells that make sensor 1's bias
  for (int s : {0, 1}) {
    const SensorCells r = SumSensorCells(tallies, s, projected, paths);
    PrintLargestCellBiases(s, r, projected, solid, basis, scene.window(), parts, args.top);
  }
  return 0;
}
