#pragma once

// The indoor stage of one scene for many blind designs on the CPU, as an optimization
// needs it: the same random streams as ComputeIndoorStage (common random numbers) and the
// same I, up to the order of floating-point sums, at a fraction of the cost.
//
// Each path is traced once through the room without the blind, up to where it could first
// meet the blind of any design within the scene's ranges (the blind's envelope,
// EnvelopeOfBlind). Until then the path does not depend on the design, except for the
// shadow rays of its next-event estimates, which all run towards the window and so past
// the blind. Per design, those recorded shadow rays are tested against the slats' layout
// alone (LocalSlatsOfBlind; here each kept as its line across the envelope, a few flops per
// design), and the paths that reached the envelope are traced on from there through the
// room and the blind (on the GPU, the room's BVH recorded once with the slats' put beside it
// per design, BvhWithSlats). Here the records follow each path on as if there were no blind
// (RecordingMode::GoesOn), and a design traces it on only from the first ray its slats block.
// With several windows, each blind has its envelope (LocalEnvelopes): a record that enters
// one is tested against that blind's slats alone, one that enters several against all.
#include <memory>
#include <vector>

#include "absl/status/statusor.h"
#include "core/dc/two_stage.h"
#include "core/trace/indoor_replay_modes.h"
#include "core/trace/local_slats.h"
#include "core/trace/trace_geometry.h"

namespace fenestra {

// The envelope of the blinds of `scene`'s ranges (with room to spare) in `geometry`'s frame:
// of the scene's blind (Scene::BlindWindow), or of the blind of `window`, which has one.
LocalEnvelope LocalEnvelopeOfBlind(const TraceGeometry& geometry, const Scene& scene);
LocalEnvelope LocalEnvelopeOfBlind(const TraceGeometry& geometry, const SceneWindow& window);
// Those of every window's blind, in the scene's order: what a replay records against.
// Unimplemented for a scene of more than kMaxReplayBlinds blinds (traced in full instead),
// InvalidArgument for one without a blind.
absl::StatusOr<LocalEnvelopes> LocalEnvelopesOfBlinds(const TraceGeometry& geometry,
                                                      const Scene& scene);

// The slats of `scene`'s blind at `design` in `geometry`'s frame, for the replays' shadow
// rays: one test of the ray's line or a few box tests instead of a traversal of the blind's
// triangles (bench/README.md, "Racing"). A ray that grazes a slat's edge within float
// rounding, about one in a million, may be answered otherwise than by the triangles.
LocalSlats LocalSlatsOfBlind(const TraceGeometry& geometry, const Scene& scene,
                             const BlindDesign& design);
LocalSlats LocalSlatsOfBlind(const TraceGeometry& geometry, const SceneWindow& window,
                             const BlindDesign& design);
// Every blind's slats at `design`, in the order of `envelopes` (LocalEnvelopesOfBlinds),
// shifted from their envelopes' centres.
ReplayBlinds ReplayBlindsOf(const TraceGeometry& geometry, const Scene& scene,
                            const BlindDesign& design, const LocalEnvelopes& envelopes);

// The corners of the slats of every blind, 8 per slat in SlatBoxes::Corner's order, as the
// blinds' mesh has them in `geometry`'s frame (AssembleMesh, then PrepareTraceGeometry), one
// blind after the other; `slats_per_blind`, where given, gets each blind's count. BvhWithSlats
// makes the mesh's triangles from them.
std::vector<Vec3f> LocalSlatCorners(const TraceGeometry& geometry, const Scene& scene,
                                    const BlindDesign& design,
                                    std::vector<int>* slats_per_blind = nullptr);

// Whether a replay follows `scene`'s blinds: it has one, and at most kMaxReplayBlinds.
bool ReplayFollows(const Scene& scene);

// InvalidArgument unless `design` has a blind within the ranges of `scene`'s blinds (a replay
// is only valid there) and a finish of the scene's materials for each.
absl::Status CheckReplayDesign(const Scene& scene, const BlindDesign& design);

class IndoorReplay : public IndoorStages {
 public:
  // Traces the design-independent part of the indoor paths of `options` (threads, seed,
  // paths, bounces, basis, parts, batches as in ComputeIndoorStage) for the designs within
  // the ranges of the scene's blind. InvalidArgument for bad options or a scene without a
  // blind.
  static absl::StatusOr<std::unique_ptr<IndoorReplay>> Record(const Scene& scene,
                                                              const IndoorOptions& options);
  ~IndoorReplay() override;
  IndoorReplay(const IndoorReplay&) = delete;
  IndoorReplay& operator=(const IndoorReplay&) = delete;

  // I for `design`, whose values must lie within the scene's ranges (InvalidArgument
  // otherwise). rays_traced counts the rays traced for this design.
  absl::StatusOr<IndoorResult> Compute(const BlindDesign& design) const override;
  absl::StatusOr<IndoorTally> TraceParts(const BlindDesign& design, int first,
                                         int last) const override;
  bool TracesInParts() const override { return true; }

  // Of all paths, the fraction that reached the envelope (a design traces on those whose rays
  // there its slats block).
  double ResumedFraction() const;
  // Wall time of Record [s].
  double RecordSeconds() const;

 private:
  struct Data;
  explicit IndoorReplay(std::unique_ptr<Data> data);
  std::unique_ptr<Data> data_;
};

}  // namespace fenestra
