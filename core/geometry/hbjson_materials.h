// The materials of a Honeybee model's elements, as honeybee-radiance assigns them: an
// element's own modifier (properties.radiance.modifier), else its room's modifier set's for its
// kind and boundary condition, else honeybee-radiance's generic defaults (its library's
// radiance_default.json, honeybee-standards). Plastic, Metal, Trans and Glass become scene
// materials of the same parameters, grey by the photopic luminance 0.265 R + 0.670 G +
// 0.065 B; Void leaves the element out.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "core/geometry/hbjson_json.h"
#include "fenestra/v1/scene.pb.h"

namespace fenestra::hbjson {

// Most modifiers and modifier sets a model may define.
inline constexpr size_t kMaxModifiers = 100'000;

// Which modifier of a modifier set an element takes (honeybee-radiance's ModifierSet:
// get_face_modifier, get_aperture_modifier, get_door_modifier, get_shade_modifier).
enum class Slot {
  kWallExterior,
  kWallInterior,
  kFloorExterior,
  kFloorInterior,
  kRoofCeilingExterior,
  kRoofCeilingInterior,
  kWindow,            // aperture to the outdoors in a wall
  kSkylight,          // aperture to the outdoors in a floor or roof
  kOperableWindow,    // aperture to the outdoors that opens
  kInteriorAperture,  // aperture to another room
  kDoorExterior,
  kDoorOverhead,  // door to the outdoors in a floor or roof
  kDoorExteriorGlass,
  kDoorInterior,
  kDoorInteriorGlass,
  kShadeExterior,
  kShadeInterior,
  kContext,  // a detached shade of no room (honeybee-radiance's generic_context)
};
inline constexpr int kSlotCount = static_cast<int>(Slot::kContext) + 1;

// What an element is made of.
struct Assigned {
  std::string material;  // name in the scene's materials; empty for a Void modifier
  bool is_glass = false;
  bool is_void() const { return material.empty(); }
};

class Modifiers {
 public:
  // Reads the modifiers and modifier sets of model.properties.radiance (`radiance`; absent:
  // none).
  static absl::StatusOr<Modifiers> Read(const std::optional<Json>& radiance);

  // The modifier set of a room: its properties.radiance.modifier_set (one of the model's, or
  // of honeybee-radiance's four generic ones), else the generic visible one. An index for For.
  absl::StatusOr<int> RoomSet(const Json& room) const;
  // The set of elements without a room.
  static constexpr int kGenericSet = 0;

  // The material of `element`: its properties.radiance.modifier, else `slot` of modifier set
  // `set`. Adds it to the scene's materials the first time.
  absl::StatusOr<Assigned> For(const Json& element, int set, Slot slot);

  // The scene's materials, in the order of first use.
  const std::vector<v1::Material>& materials() const { return materials_; }

 private:
  struct Set {
    std::string identifier;
    // Per slot: a modifier of the model, a generic one (by identifier), or none
    std::optional<std::string> model[kSlotCount];
  };

  absl::Status ReadModifier(const Json& modifier);
  absl::Status ReadSet(const Json& set);
  // The modifier of the model (`generic` false) or of honeybee-radiance's defaults named `id`,
  // as a scene material; `where` names the reference in errors.
  absl::StatusOr<Assigned> Use(const std::string& id, bool generic, const Json& where);
  absl::StatusOr<v1::Material> Build(const Json& modifier, const std::string& name);

  std::map<std::string, Json> model_modifiers_;
  std::vector<Set> sets_;  // after the four generic ones (which have no entry)
  std::map<std::pair<std::string, bool>, Assigned> used_;
  std::vector<v1::Material> materials_;
};

}  // namespace fenestra::hbjson
