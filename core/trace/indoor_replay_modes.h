#pragma once

// What the indoor replay (core/dc/indoor_replay.h) shares between the CPU and the GPU:
// the blinds' envelopes in the trace frame, the records of the design-independent part of a
// path, and the intersector, sink and mode that make them while IndoorMode traces. A scene
// may have up to kMaxReplayBlinds blinds (one per window); a record that meets one envelope
// names it, and one that meets several is tested against every blind.
//
// A Recorder takes the records:
//   void BeginPath();                                a path starts
//   void AddFixed(int column, double value);        light no blind can change
//   void AddConnection(const ReplayConnection& c);   counts unless the blind blocks c
//   void AddTouch(ReplayTouch touch);               the path reached the envelope
// A path that reaches the envelope is traced on per design from there, unless its ray
// crosses the envelope from face to face and the design's slats leave that line clear: then
// it goes on as in the room without the blind. RecordingMode follows it on (GoesOn: the
// CPU's replay), and what it records after a touch counts only for the designs that leave the
// path's lines up to there clear. The GPU's records end at the first touch: the path is traced on
// from there at every design.
#include <cmath>
#include <cstdint>

#include "core/common/cpu_gpu.h"
#include "core/trace/local_slats.h"
#include "core/trace/path.h"
#include "core/trace/two_stage_modes.h"

namespace fenestra {

// The envelope of every blind of a design space (EnvelopeOfBlind), in the trace frame.
struct LocalEnvelope {
  Vec3f center;
  Vec3f axis[3];  // unit
  float half[3];

  // Whether origin + t direction, t in [0, extent], enters the box.
  FENESTRA_CPU_GPU bool Touches(Vec3f origin, Vec3f direction, float extent) const {
    float t0 = 0.0f, t1 = extent;
    const Vec3f o = origin - center;
    for (int k = 0; k < 3; ++k) {
      const float ok = Dot(o, axis[k]), vk = Dot(direction, axis[k]);
      if (vk == 0.0f) {
        if (fabsf(ok) > half[k]) return false;
        continue;
      }
      float ta = (-half[k] - ok) / vk, tb = (half[k] - ok) / vk;
      if (ta > tb) {
        const float t = ta;
        ta = tb;
        tb = t;
      }
      t0 = t0 < ta ? ta : t0;
      t1 = tb < t1 ? tb : t1;
      if (t0 > t1) return false;
    }
    return true;
  }
};

// The most blinds a replay follows; a scene with more is traced in full per design.
inline constexpr int kMaxReplayBlinds = 4;

// The envelopes of a scene's blinds (one per window with a blind, in the scene's order).
struct LocalEnvelopes {
  LocalEnvelope blind[kMaxReplayBlinds];
  int count = 0;

  static constexpr int kNone = -1, kSeveral = -2;
  // The one envelope that origin + t direction, t in [0, extent], enters; kNone or kSeveral.
  FENESTRA_CPU_GPU int Touched(Vec3f origin, Vec3f direction, float extent) const {
    int touched = kNone;
    for (int b = 0; b < count; ++b) {
      if (!blind[b].Touches(origin, direction, extent)) continue;
      if (touched != kNone) return kSeveral;
      touched = b;
    }
    return touched;
  }
};

// A design's slats of each blind (LocalSlatsOfBlind), with their centres from their
// envelopes' (LocalSlats::ShiftFrom), for the replays' tests.
struct ReplayBlinds {
  LocalSlats slats[kMaxReplayBlinds];
  Vec3f shift[kMaxReplayBlinds];
  int count = 0;

  // Whether any blind meets the segment.
  FENESTRA_CPU_GPU bool Occluded(Vec3f origin, Vec3f direction, float distance) const {
    for (int b = 0; b < count; ++b) {
      if (slats[b].Occluded(origin, direction, distance)) return true;
    }
    return false;
  }
};

// A next-event estimate whose shadow ray cleared the room: it counts unless the blind
// blocks the ray.
struct ReplayConnection {
  Vec3f origin;
  Vec3f direction;
  float distance;
  int32_t column;  // of I: a window cell or a direct column (decided when recorded)
  double value;
};

// A connection whose shadow ray crosses the envelope's depth from face to face, as nearly all
// do: its line across the envelope (in the envelope's frame) stands for the ray.
struct ReplayCrossing {
  SlabCrossing line;
  int32_t column;
  int32_t blind;  // whose envelope
  double value;
};

// `c` as a crossing of `envelope` (axes: along the stack, along the slats, into the room),
// when its shadow ray crosses it.
FENESTRA_CPU_GPU inline bool CrossingOf(const LocalEnvelope& envelope, const ReplayConnection& c,
                                        ReplayCrossing* crossing) {
  const StackSegment s = SegmentInFrame(envelope.center, envelope.axis[0], envelope.axis[1],
                                        envelope.axis[2], c.origin, c.direction, c.distance);
  crossing->column = c.column;
  crossing->blind = 0;
  crossing->value = c.value;
  return SlabCrossing::Of(s, envelope.half[2], &crossing->line);
}

// What a connection is to the blinds: light none can block (its shadow ray enters no
// envelope), a crossing of one envelope (*crossing), or one tested against every blind.
enum class ConnectionKind { kFixed, kCrossing, kOther };
FENESTRA_CPU_GPU inline ConnectionKind KindOf(const LocalEnvelopes& envelopes,
                                              const ReplayConnection& c, ReplayCrossing* crossing) {
  const int b = envelopes.Touched(c.origin, c.direction, c.distance);
  if (b == LocalEnvelopes::kNone) return ConnectionKind::kFixed;
  if (b >= 0 && CrossingOf(envelopes.blind[b], c, crossing)) {
    crossing->blind = b;
    return ConnectionKind::kCrossing;
  }
  return ConnectionKind::kOther;
}

// Whether `slats` leave crossing `k` of `envelope` clear; `shift` is ShiftFrom(envelope.center).
FENESTRA_CPU_GPU inline bool Clear(const LocalSlats& slats, Vec3f shift,
                                   const LocalEnvelope& envelope, const ReplayCrossing& k) {
  return !slats.Occluded(k.line, shift, envelope.half[2]);
}

// Whether `blinds` leave crossing `k` of `envelopes` clear.
FENESTRA_CPU_GPU inline bool Clear(const ReplayBlinds& blinds, const LocalEnvelopes& envelopes,
                                   const ReplayCrossing& k) {
  return Clear(blinds.slats[k.blind], blinds.shift[k.blind], envelopes.blind[k.blind], k);
}

// A path that reached the envelope, as the GPU keeps it: its state there and its index
// (random stream).
struct ReplayResume {
  PathState state;
  uint64_t path;
};

// Where a recorded path reached an envelope: its state there, its index (random stream)
// and, when its ray enters that envelope alone and crosses it from face to face, that ray's
// line there.
struct ReplayTouch {
  PathState state;
  uint64_t path;
  SlabCrossing line;
  int32_t blind;  // whose envelope
  bool crosses;
};

// Whether `blinds` leave the line of `touch` clear, so that the path goes on as recorded.
FENESTRA_CPU_GPU inline bool Clear(const ReplayBlinds& blinds, const LocalEnvelopes& envelopes,
                                   const ReplayTouch& touch) {
  const int b = touch.blind;
  return touch.crosses &&
         !blinds.slats[b].Occluded(touch.line, blinds.shift[b], envelopes.blind[b].half[2]);
}

// The room without the blinds, stopping rays that touch an envelope (unless told to let the
// next one pass) and remembering the shadow ray a next-event estimate is about to score. One
// per thread: it holds the state of the path being traced.
template <class Room>
struct RecordingIntersector {
  Room room;
  LocalEnvelopes envelopes;
  mutable bool diverged = false;
  mutable bool crosses = false;  // the stopped ray enters one envelope and crosses it
  mutable SlabCrossing line{};   // then its line there
  mutable int32_t blind = 0;     // and whose envelope that is
  mutable bool pass = false;     // the next ray goes on through the envelope
  mutable bool connection_pending = false;
  mutable ReplayConnection pending{};

  FENESTRA_CPU_GPU bool Intersect(Vec3f origin, Vec3f direction, SurfaceHit* hit) const {
    connection_pending = false;
    const bool found = room.Intersect(origin, direction, hit);
    if (pass) {
      pass = false;
      return found;
    }
    const Vec3f to_hit = found ? hit->position - origin : Vec3f{0, 0, 0};
    const float extent = found ? sqrtf(Dot(to_hit, to_hit)) : INFINITY;
    const int b = envelopes.Touched(origin, direction, extent);
    if (b != LocalEnvelopes::kNone) {
      diverged = true;
      ReplayCrossing crossing;
      crosses =
          b >= 0 && CrossingOf(envelopes.blind[b],
                               ReplayConnection{origin, direction, extent, 0, 0.0}, &crossing);
      line = crossing.line;
      blind = b >= 0 ? b : 0;
      return false;
    }
    return found;
  }

  FENESTRA_CPU_GPU bool Occluded(Vec3f origin, Vec3f direction, float distance) const {
    const bool blocked = room.Occluded(origin, direction, distance);
    connection_pending = !blocked;
    pending = ReplayConnection{origin, direction, distance, 0, 0.0};
    return blocked;
  }
};

// IndoorMode's contributions: a scored shadow ray becomes a connection, anything else (a
// bounce ray leaving through the window without touching the envelope) is fixed. The
// column (direct or window cell) depends on the outdoor surfaces only, so it is decided
// here, once for every design.
template <class Room, class Recorder>
struct RecordingSink {
  const RecordingIntersector<Room>* scene;
  Recorder* recorder;

  FENESTRA_CPU_GPU void Add(int column, double value) {
    if (scene->connection_pending) {
      ReplayConnection c = scene->pending;
      c.column = column;
      c.value = value;
      recorder->AddConnection(c);
      scene->connection_pending = false;
    } else {
      recorder->AddFixed(column, value);
    }
  }
};

// IndoorMode through the recording intersector; a ray stopped at the envelope is kept to
// be resumed, not scored.
template <class Room, class Recorder, class Outdoor>
struct RecordingMode {
  IndoorMode<RecordingSink<Room, Recorder>, Outdoor> inner;
  const RecordingIntersector<Room>* scene;
  Recorder* recorder;
  uint64_t path = 0;

  template <class Intersector>
  FENESTRA_CPU_GPU PathState Start(const Intersector& s, const PathRandom& random) {
    path = random.path();
    touched = false;
    recorder->BeginPath();
    return inner.Start(s, random);
  }
  template <class Intersector>
  FENESTRA_CPU_GPU void AtReflection(const Intersector& s, const PathState& state,
                                     const ReflectionVertex& vertex, const PathRandom& random) {
    inner.AtReflection(s, state, vertex, random);
  }
  // A ray stopped at the envelope: recorded, and let through when the path is followed on
  // (TracePath steps it again, GoesOn).
  FENESTRA_CPU_GPU void Escape(const PathState& state) {
    if (scene->diverged) {
      scene->diverged = false;
      recorder->AddTouch(ReplayTouch{state, path, scene->line, scene->blind, scene->crosses});
      // A ray that does not cross is traced on at every design: nothing after it counts
      touched = follow && scene->crosses;
    } else {
      inner.Escape(state);
    }
  }
  FENESTRA_CPU_GPU void Finish(const PathStats& stats) { inner.Finish(stats); }

  // After a step that ended: whether the path goes on through the envelope (step it again
  // from the same state).
  FENESTRA_CPU_GPU bool GoesOn() {
    if (!touched) return false;
    touched = false;
    scene->pass = true;
    return true;
  }

  bool touched = false;  // the last step stopped at the envelope, and the path goes on
  // Whether a path goes on past the envelope, so that its records say what it did beyond
  // (the CPU's); else its records end at its first touch (the GPU's: bench/README.md,
  // "Paths followed beyond the envelope")
  bool follow = true;
};

// A path's stats before its first step from a touch.
FENESTRA_CPU_GPU inline PathStats ResumedStats(const PathState& state) {
  return PathStats{0, state.weight, PathEnd::kEscaped, 0, {0, 0, 0, 0, 0, 0}};
}

}  // namespace fenestra
