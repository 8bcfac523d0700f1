#include "core/dc/indoor_replay.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <span>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/common/seconds.h"
#include "core/common/status_macros.h"
#include "core/common/thread_pool.h"
#include "core/dc/backend_support.h"
#include "core/trace/embree_scene.h"
#include "core/trace/one_stage_cpu.h"
#include "core/trace/trace_geometry.h"
#include "core/trace/two_stage_cpu.h"

namespace fenestra {
namespace {

// Room to spare around the blind's envelope: far above float rounding at room scale [m]
constexpr double kEnvelopeMargin = 1e-3;

// Light no blind can change, once a path has gone beyond the envelope.
struct FixedLight {
  int32_t column;
  double value;
};

// Where a recorded path reached an envelope, and what it did after in the room without the
// blinds (RecordingMode::GoesOn): its records in the chunk's `after_*` from these indices on, up
// to the next touch's, count for a design that leaves this touch's line, and the path's earlier
// ones, clear.
struct Touch {
  ReplayTouch touch;
  bool first;                            // the path's first touch
  uint32_t crossings[kMaxReplayBlinds];  // per blind
  uint32_t others, fixed;
};

// Connections that cross the envelope, kept as columns so that a design's tests of their
// lines run several at a time (SIMD).
struct Crossings {
  std::vector<float> intercept, slope, l_enter, l_leave;
  std::vector<int32_t> column;
  std::vector<double> value;

  void Add(const ReplayCrossing& k) {
    intercept.push_back(k.line.intercept);
    slope.push_back(k.line.slope);
    l_enter.push_back(k.line.l_enter);
    l_leave.push_back(k.line.l_leave);
    column.push_back(k.column);
    value.push_back(k.value);
  }
  size_t size() const { return column.size(); }
  SlabCrossing Line(size_t i) const { return {intercept[i], slope[i], l_enter[i], l_leave[i]}; }
};

// The recorded paths of one sensor, one batch, one range of path indices.
struct Chunk {
  uint32_t sensor = 0;
  int batch = 0;
  std::vector<double> fixed;  // per column of I: what no blind can change
  const LocalEnvelopes* envelopes = nullptr;
  // Connections before a path reaches an envelope: those that cross one, per blind
  Crossings crossings[kMaxReplayBlinds];
  std::vector<ReplayConnection> others;  // tested against every blind
  std::vector<Touch> touches;
  // What paths did beyond the envelopes, in the order of their touches
  Crossings after_crossings[kMaxReplayBlinds];
  std::vector<ReplayConnection> after_others;
  std::vector<FixedLight> after_fixed;
  uint64_t paths = 0;
  bool beyond = false;  // the path being recorded has reached an envelope

  void BeginPath() { beyond = false; }
  void AddFixed(int column, double value) {
    if (beyond) {
      after_fixed.push_back({column, value});
    } else {
      fixed[column] += value;
    }
  }
  void AddConnection(const ReplayConnection& c) {
    ReplayCrossing crossing;
    switch (KindOf(*envelopes, c, &crossing)) {
      case ConnectionKind::kFixed:
        AddFixed(c.column, c.value);
        return;
      case ConnectionKind::kCrossing:
        (beyond ? after_crossings : crossings)[crossing.blind].Add(crossing);
        return;
      case ConnectionKind::kOther:
        (beyond ? after_others : others).push_back(c);
        return;
    }
  }
  void AddTouch(const ReplayTouch& touch) {
    Touch t{touch,
            !beyond,
            {},
            static_cast<uint32_t>(after_others.size()),
            static_cast<uint32_t>(after_fixed.size())};
    for (int b = 0; b < kMaxReplayBlinds; ++b) {
      t.crossings[b] = static_cast<uint32_t>(after_crossings[b].size());
    }
    touches.push_back(t);
    beyond = true;
  }
};

using OutdoorEmbreeView = OutdoorView<EmbreeIntersector>;
using Recording = RecordingIntersector<EmbreeIntersector>;

// Adds the value of every connection that `slats` leave clear to its column of `sum`: the
// crossings [first, last) of `crossings` of `envelope`; `shift` is where the slats' centre
// lies in the envelope's frame (ShiftFrom). A crossing's test is a few flops without a branch
// (LocalSlats::LineOccluded), run over a block of lines at a time, then added times 0 or 1
// rather than by a branch the CPU would mispredict for a third of the rays.
void TestCrossings(const LocalSlats& slats, Vec3f shift, const LocalEnvelope& envelope,
                   const Crossings& crossings, size_t first, size_t last,
                   std::vector<double>& sum) {
  constexpr size_t kBlock = 256;
  float clear[kBlock];  // 1 or 0, or -1 where the line does not answer for the crossing
  const float half_depth = envelope.half[2];
  for (size_t begin = first; begin < last; begin += kBlock) {
    const size_t count = std::min(kBlock, last - begin);
    const float* intercept = crossings.intercept.data() + begin;
    const float* slope = crossings.slope.data() + begin;
    const float* l_enter = crossings.l_enter.data() + begin;
    const float* l_leave = crossings.l_leave.data() + begin;
    for (size_t i = 0; i < count; ++i) {
      const SlabCrossing line{intercept[i], slope[i], l_enter[i], l_leave[i]};
      const bool occluded = slats.LineOccludedAt(line, shift);
      clear[i] = slats.LineAnswers(line, shift, half_depth) ? (occluded ? 0.0f : 1.0f) : -1.0f;
    }
    for (size_t i = 0; i < count; ++i) {
      float c = clear[i];
      if (c < 0.0f) c = slats.Occluded(crossings.Line(begin + i), shift, half_depth) ? 0.0f : 1.0f;
      sum[crossings.column[begin + i]] += crossings.value[begin + i] * c;
    }
  }
}

// TestCrossings for each blind's crossings [first[b], last[b]), then the connections `others`
// tested against every blind. The tests made.
uint64_t TestConnections(const ReplayBlinds& blinds, const LocalEnvelopes& envelopes,
                         const Crossings* crossings, const uint32_t* first, const uint32_t* last,
                         std::span<const ReplayConnection> others, std::vector<double>& sum) {
  uint64_t tests = others.size();
  for (int b = 0; b < blinds.count; ++b) {
    TestCrossings(blinds.slats[b], blinds.shift[b], envelopes.blind[b], crossings[b], first[b],
                  last[b], sum);
    tests += last[b] - first[b];
  }
  for (const ReplayConnection& k : others) {
    if (!blinds.Occluded(k.origin, k.direction, k.distance)) sum[k.column] += k.value;
  }
  return tests;
}

// Follows each path of `chunk` beyond the envelopes while `blinds` leave its lines clear,
// adding what it did there to `sum`; a path whose line they block, or whose ray does not
// cross one envelope alone, goes to `resume` from that touch. The tests made.
template <class Resume>
uint64_t FollowTouches(const ReplayBlinds& blinds, const Chunk& chunk, std::vector<double>& sum,
                       Resume resume) {
  uint64_t tests = 0;
  bool following = false;
  const size_t count = chunk.touches.size();
  for (size_t t = 0; t < count; ++t) {
    const Touch& touch = chunk.touches[t];
    following = following || touch.first;
    if (!following) continue;
    ++tests;
    if (!Clear(blinds, *chunk.envelopes, touch.touch)) {
      resume(touch.touch);
      following = false;
      continue;
    }
    const bool last = t + 1 == count;
    uint32_t crossings[kMaxReplayBlinds];
    for (int b = 0; b < kMaxReplayBlinds; ++b) {
      crossings[b] = last ? static_cast<uint32_t>(chunk.after_crossings[b].size())
                          : chunk.touches[t + 1].crossings[b];
    }
    const size_t others = last ? chunk.after_others.size() : chunk.touches[t + 1].others;
    const size_t fixed = last ? chunk.after_fixed.size() : chunk.touches[t + 1].fixed;
    tests += TestConnections(
        blinds, *chunk.envelopes, chunk.after_crossings, touch.crossings, crossings,
        std::span(chunk.after_others).subspan(touch.others, others - touch.others), sum);
    for (size_t k = touch.fixed; k < fixed; ++k) {
      sum[chunk.after_fixed[k].column] += chunk.after_fixed[k].value;
    }
  }
  return tests;
}

bool WithinRange(double value, const ParameterRange& range) {
  return value >= range.min && value <= range.max;
}

}  // namespace

LocalEnvelope LocalEnvelopeOfBlind(const TraceGeometry& geometry, const Scene& scene) {
  return LocalEnvelopeOfBlind(geometry, scene.BlindWindow());
}

LocalEnvelope LocalEnvelopeOfBlind(const TraceGeometry& geometry, const SceneWindow& window) {
  const BlindEnvelope envelope = EnvelopeOfBlind(window.window, *window.blind, kEnvelopeMargin);
  LocalEnvelope local;
  local.center = geometry.ToLocal(envelope.center);
  for (int k = 0; k < 3; ++k) {
    const Vec3d a = envelope.axis[k];
    local.axis[k] = {static_cast<float>(a.x), static_cast<float>(a.y), static_cast<float>(a.z)};
    local.half[k] = static_cast<float>(envelope.half_extent[k]);
  }
  return local;
}

absl::StatusOr<LocalEnvelopes> LocalEnvelopesOfBlinds(const TraceGeometry& geometry,
                                                      const Scene& scene) {
  if (!scene.blind()) return absl::InvalidArgumentError("the scene has no blind to vary");
  LocalEnvelopes envelopes;
  for (const SceneWindow& w : scene.windows) {
    if (!w.blind) continue;
    if (envelopes.count == kMaxReplayBlinds) {
      return absl::UnimplementedError(
          absl::StrCat("the indoor replay follows at most ", kMaxReplayBlinds,
                       " blinds (the stages trace this scene per design instead)"));
    }
    envelopes.blind[envelopes.count++] = LocalEnvelopeOfBlind(geometry, w);
  }
  return envelopes;
}

ReplayBlinds ReplayBlindsOf(const TraceGeometry& geometry, const Scene& scene,
                            const BlindDesign& design, const LocalEnvelopes& envelopes) {
  ReplayBlinds blinds;
  for (const SceneWindow& w : scene.windows) {
    if (!w.blind || blinds.count == envelopes.count) continue;
    const int b = blinds.count++;
    blinds.slats[b] = LocalSlatsOfBlind(geometry, w, design);
    blinds.shift[b] = blinds.slats[b].ShiftFrom(envelopes.blind[b].center);
  }
  return blinds;
}

LocalSlats LocalSlatsOfBlind(const TraceGeometry& geometry, const Scene& scene,
                             const BlindDesign& design) {
  return LocalSlatsOfBlind(geometry, scene.BlindWindow(), design);
}

LocalSlats LocalSlatsOfBlind(const TraceGeometry& geometry, const SceneWindow& window,
                             const BlindDesign& design) {
  const SlatStack stack = StackOfBlind(window.window, *window.blind, design);
  const auto axis = [](Vec3d v) {
    return Vec3f{static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)};
  };
  LocalSlats slats;
  slats.center = geometry.ToLocal(stack.center);
  slats.stack = axis(stack.stack);
  slats.length = axis(stack.length);
  slats.into_room = axis(stack.into_room);
  slats.pitch = static_cast<float>(stack.pitch_m);
  slats.half_length = static_cast<float>(stack.half_length_m);
  slats.half_width = static_cast<float>(stack.half_width_m);
  slats.half_thickness = static_cast<float>(stack.half_thickness_m);
  slats.cos_tilt = static_cast<float>(std::cos(stack.tilt_rad));
  slats.sin_tilt = static_cast<float>(std::sin(stack.tilt_rad));
  slats.reach = static_cast<float>(std::hypot(stack.half_width_m, stack.half_thickness_m));
  slats.depth = static_cast<float>(stack.half_width_m * std::abs(std::sin(stack.tilt_rad)) +
                                   stack.half_thickness_m * std::abs(std::cos(stack.tilt_rad)));
  slats.count = stack.count;
  return slats;
}

std::vector<Vec3f> LocalSlatCorners(const TraceGeometry& geometry, const Scene& scene,
                                    const BlindDesign& design, std::vector<int>* slats_per_blind) {
  std::vector<Vec3f> corners;
  if (slats_per_blind != nullptr) slats_per_blind->clear();
  for (const SceneWindow& w : scene.windows) {
    if (!w.blind) continue;
    const SlatBoxes boxes = BoxesOfStack(StackOfBlind(w.window, *w.blind, design));
    for (int k = 0; k < boxes.count; ++k) {
      for (int i = 0; i < 8; ++i) corners.push_back(geometry.ToLocal(boxes.Corner(k, i)));
    }
    if (slats_per_blind != nullptr) slats_per_blind->push_back(boxes.count);
  }
  return corners;
}

bool ReplayFollows(const Scene& scene) {
  const auto blinds = std::count_if(scene.windows.begin(), scene.windows.end(),
                                    [](const SceneWindow& w) { return w.blind.has_value(); });
  return blinds > 0 && blinds <= kMaxReplayBlinds;
}

absl::Status CheckReplayDesign(const Scene& scene, const BlindDesign& design) {
  if (!scene.blind()) return absl::InvalidArgumentError("the scene has no blind to vary");
  if (!design.has_blind) {
    return absl::InvalidArgumentError(
        "the design lies outside the ranges the indoor paths were recorded for");
  }
  for (const SceneWindow& w : scene.windows) {
    if (!w.blind) continue;
    const BlindSpec& spec = *w.blind;
    if (!WithinRange(design.tilt_rad, spec.tilt_rad) ||
        !WithinRange(design.slat_width_m, spec.slat_width_m) ||
        !WithinRange(design.slat_spacing_m, spec.slat_spacing_m) ||
        !WithinRange(design.slat_thickness_m, spec.slat_thickness_m)) {
      return absl::InvalidArgumentError(
          "the design lies outside the ranges the indoor paths were recorded for");
    }
    const SlatFinish finish = FinishOf(spec, design);
    if (std::max(finish.material, finish.outer_material) >= scene.materials.size()) {
      return absl::InvalidArgumentError("the design's slat finish names no material of the scene");
    }
  }
  return absl::OkStatus();
}

struct IndoorReplay::Data {
  Scene scene;
  IndoorOptions options;
  HemisphereBasis basis;
  Vec3d origin;  // the trace frame of every geometry here
  std::vector<TraceSensor> sensors;
  std::vector<TraceWindow> windows;  // the scene's windows (LocalWindows)
  TraceWindows Windows() const { return ViewOfWindows(windows, basis); }
  std::unique_ptr<EmbreeScene> outdoor;  // the outdoor surfaces, for the direct test
  std::vector<uint8_t> met;              // the window cells whose views all meet them
  OutdoorEmbreeView outdoor_view;
  LocalEnvelopes envelopes;  // the frames of the chunks' connections
  std::vector<Chunk> chunks;
  int columns = 0;  // of I
  uint64_t resumed = 0;
  double record_seconds = 0;
};

IndoorReplay::IndoorReplay(std::unique_ptr<Data> data) : data_(std::move(data)) {}
IndoorReplay::~IndoorReplay() = default;

absl::StatusOr<std::unique_ptr<IndoorReplay>> IndoorReplay::Record(const Scene& scene,
                                                                   const IndoorOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (!scene.blind()) return absl::InvalidArgumentError("the scene has no blind to vary");
  auto data = std::make_unique<Data>();
  data->scene = scene;
  data->options = options;
  FENESTRA_ASSIGN_OR_RETURN(basis, CheckIndoorOptions(options));
  data->basis = basis;

  // The room without the blind, in the frame of the room with it (the blind lies inside
  // the room's bounds, so both frames are the same)
  const TriangleMesh room = SelectSide(scene.fixed, Side::kIndoor);
  FENESTRA_ASSIGN_OR_RETURN(geometry, PrepareTraceGeometry(room, scene.materials));
  data->origin = geometry.origin;
  FENESTRA_ASSIGN_OR_RETURN(embree, EmbreeScene::Build(geometry));
  data->sensors = LocalSensors(geometry, scene.sensors);
  data->windows = LocalWindows(geometry, scene, options.parts, basis);
  data->columns = IndoorColumnCount(ViewOfWindows(data->windows, basis));
  FENESTRA_ASSIGN_OR_RETURN(outdoor, OutdoorViewGeometry(scene));
  FENESTRA_ASSIGN_OR_RETURN(outdoor_scene, EmbreeScene::Build(outdoor));
  data->outdoor = std::move(outdoor_scene);
  data->met = OutdoorMetCells(geometry, outdoor, data->windows, basis);
  data->outdoor_view = {data->outdoor->Intersector(), OutdoorOffset(geometry, outdoor),
                        data->met.data()};
  FENESTRA_ASSIGN_OR_RETURN(envelopes, LocalEnvelopesOfBlinds(geometry, scene));
  data->envelopes = envelopes;

  // Chunks: (sensor, batch, part of the batch), as TraceIndoorCpu
  const int batches = options.batches;
  const uint64_t paths = static_cast<uint64_t>(options.paths_per_sensor);
  const uint64_t parts = kDesignParts;
  data->chunks.resize(data->sensors.size() * batches * parts);
  const PathSettings settings = IndoorPathSettings(options);
  ParallelFor(data->chunks.size(), ResolveThreadCount(options.threads), [&](uint64_t c) {
    Chunk& chunk = data->chunks[c];
    chunk.sensor = static_cast<uint32_t>(c / (batches * parts));
    chunk.batch = static_cast<int>((c / parts) % batches);
    const int part = static_cast<int>(c % parts);
    const uint64_t first = PartStart(paths, batches, kDesignParts, chunk.batch, part);
    const uint64_t last = PartStart(paths, batches, kDesignParts, chunk.batch, part + 1);
    chunk.fixed.assign(data->columns, 0.0);
    chunk.envelopes = &data->envelopes;
    chunk.paths = last - first;
    Recording scene_view{embree->Intersector(), data->envelopes};
    const TraceSensor& sensor = data->sensors[chunk.sensor];
    const uint64_t batch_first = BatchStart(paths, batches, chunk.batch);
    RecordingSink<EmbreeIntersector, Chunk> sink{&scene_view, &chunk};
    using Mode = RecordingMode<EmbreeIntersector, Chunk, OutdoorEmbreeView>;
    for (uint64_t p = first; p < last; ++p) {
      Mode mode{{sensor.position, sensor.normal, data->Windows(), &data->basis,
                 settings.max_bounces, &data->outdoor_view, &sink},
                &scene_view,
                &chunk};
      // Without splitting, so that a path's records are one sequence
      TracePath<Recording, Mode, 0>(
          scene_view, geometry.Surfaces(), settings,
          PathRandom(options.seed, chunk.sensor, p, settings.sequence, batch_first), mode);
    }
  });
  for (const Chunk& chunk : data->chunks) {
    for (const Touch& touch : chunk.touches) data->resumed += touch.first;
  }
  data->record_seconds = SecondsSince(start);
  return std::unique_ptr<IndoorReplay>(new IndoorReplay(std::move(data)));
}

absl::StatusOr<IndoorResult> IndoorReplay::Compute(const BlindDesign& design) const {
  const auto start = std::chrono::steady_clock::now();
  FENESTRA_ASSIGN_OR_RETURN(tally, TraceParts(design, 0, kDesignParts));
  IndoorResult result = IndoorResultFromTally(tally, data_->options);
  result.triangles = SelectSide(AssembleMesh(data_->scene, design), Side::kIndoor).TriangleCount();
  result.backend = "embree-cpu (replay)";
  result.wall_seconds = SecondsSince(start);
  return result;
}

absl::StatusOr<IndoorTally> IndoorReplay::TraceParts(const BlindDesign& design, int first,
                                                     int last) const {
  const auto start = std::chrono::steady_clock::now();
  const Data& d = *data_;
  FENESTRA_RETURN_IF_ERROR(CheckReplayDesign(d.scene, design));
  FENESTRA_RETURN_IF_ERROR(CheckDesignParts(first, last));

  // The room with this blind in the recorded frame, and the slats' layout, shifted from the
  // envelope's centre along its axes
  const TriangleMesh full = SelectSide(AssembleMesh(d.scene, design), Side::kIndoor);
  FENESTRA_ASSIGN_OR_RETURN(full_geometry,
                            PrepareTraceGeometry(full, d.scene.materials, &d.origin));
  FENESTRA_ASSIGN_OR_RETURN(full_scene, EmbreeScene::Build(full_geometry));
  const EmbreeIntersector full_view = full_scene->Intersector();
  const ReplayBlinds blinds = ReplayBlindsOf(full_geometry, d.scene, design, d.envelopes);
  const SurfaceTable surfaces = full_geometry.Surfaces();
  const PathSettings settings = IndoorPathSettings(d.options);

  struct Slot {
    std::vector<double> sum;
    TraceCounters counters;
    void Add(int cell, double value) { sum[cell] += value; }
  };
  const auto traced = std::chrono::steady_clock::now();
  IndoorTally tally;
  tally.sensors = static_cast<int>(d.sensors.size());
  tally.columns = d.columns;
  tally.batches = d.options.batches;
  tally.paths_per_sensor = static_cast<uint64_t>(d.options.paths_per_sensor);
  tally.batch_paths = PartPaths(tally.paths_per_sensor, tally.batches, kDesignParts, first, last);
  tally.threads = ResolveThreadCount(d.options.threads);
  tally.sum.assign(static_cast<size_t>(tally.batches) * tally.sensors * tally.columns, 0.0);
  // The chunks of parts [first, last) of every (sensor, batch), in the order Record made them
  const uint64_t span = static_cast<uint64_t>(last - first);
  const auto chunk_of = [&](uint64_t i) -> const Chunk& {
    return d.chunks[(i / span) * kDesignParts + first + i % span];
  };
  TraceChunksCpu<Slot>(
      span * tally.batches * tally.sensors, tally.threads,
      [&](uint64_t i, Slot& slot) {
        const Chunk& chunk = chunk_of(i);
        slot.sum = chunk.fixed;
        uint32_t counts[kMaxReplayBlinds];
        for (int b = 0; b < kMaxReplayBlinds; ++b) {
          counts[b] = static_cast<uint32_t>(chunk.crossings[b].size());
        }
        const uint32_t none[kMaxReplayBlinds] = {};
        slot.counters.rays += TestConnections(blinds, *chunk.envelopes, chunk.crossings, none,
                                              counts, chunk.others, slot.sum);
        const TraceSensor& sensor = d.sensors[chunk.sensor];
        IndoorMode<Slot, OutdoorEmbreeView> mode{
            sensor.position,      sensor.normal,   d.Windows(), &d.basis,
            settings.max_bounces, &d.outdoor_view, &slot};
        const uint64_t batch_first = BatchStart(tally.paths_per_sensor, tally.batches, chunk.batch);
        slot.counters.rays += FollowTouches(blinds, chunk, slot.sum, [&](const ReplayTouch& r) {
          PathStats stats = ResumedStats(r.state);
          PathState pending[1];
          int pending_count = 0;
          uint32_t interactions = r.state.vertex;
          const PathRandom random(d.options.seed, chunk.sensor, r.path, settings.sequence,
                                  batch_first);
          stats.end =
              path_internal::FollowBranch(full_view, surfaces, settings, random, mode, r.state,
                                          &interactions, pending, 0, &pending_count, &stats);
          slot.counters.Add(stats);
        });
      },
      [&](uint64_t i, const Slot& slot) {
        const Chunk& chunk = chunk_of(i);
        double* row = &tally.sum[(static_cast<size_t>(chunk.batch) * tally.sensors + chunk.sensor) *
                                 tally.columns];
        for (int k = 0; k < tally.columns; ++k) row[k] += slot.sum[k];
        tally.counters.Add(slot.counters);
      });
  tally.trace_seconds = SecondsSince(traced);
  tally.wall_seconds = SecondsSince(start);
  return tally;
}

double IndoorReplay::ResumedFraction() const {
  uint64_t paths = 0;
  for (const Chunk& chunk : data_->chunks) paths += chunk.paths;
  return paths > 0 ? static_cast<double>(data_->resumed) / static_cast<double>(paths) : 0.0;
}

double IndoorReplay::RecordSeconds() const { return data_->record_seconds; }

}  // namespace fenestra
