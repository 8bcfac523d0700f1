#include "core/geometry/hbjson_materials.h"

#include <google/protobuf/util/message_differencer.h>

#include <algorithm>
#include <cctype>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/common/text.h"
#include "core/geometry/material.h"
#include "core/trace/glass.h"  // header-only: the pane's formulas, shared with the tracer

namespace fenestra::hbjson {
namespace {

// honeybee-radiance's generic modifiers (honeybee-standards, radiance_default.json): grey
// plastics of a reflectance, glasses of a transmissivity (index 1.52).
struct GenericModifier {
  const char* identifier;
  bool glass;
  double value;  // plastic: reflectance; glass: transmissivity
};
constexpr GenericModifier kGenericModifiers[] = {
    {"generic_floor_0.20", false, 0.2},
    {"generic_wall_0.50", false, 0.5},
    {"generic_ceiling_0.80", false, 0.8},
    {"generic_opaque_door_0.50", false, 0.5},
    {"generic_interior_shade_0.50", false, 0.5},
    {"generic_exterior_shade_0.35", false, 0.35},
    {"generic_context_0.20", false, 0.2},
    {"generic_interior_window_vis_0.88", true, 0.9584154328610596},
    {"generic_exterior_window_vis_0.64", true, 0.6975761815384331},
    {"generic_exterior_screened_window_vis_0.32", true, 0.34901895091031854},
    {"generic_interior_window_sol_0.77", true, 0.8389405447251757},
    {"generic_exterior_window_sol_0.37", true, 0.4035231572885182},
    {"generic_exterior_screened_window_sol_0.19", true, 0.2072595906234098},
    {"generic_floor_exterior_side_0.50", false, 0.5},
    {"generic_wall_exterior_side_0.35", false, 0.35},
    {"generic_ceiling_exterior_side_0.35", false, 0.35},
    {"air_boundary", true, 1.0},
    {"black", false, 0.0},
};

const GenericModifier* FindGeneric(const std::string& id) {
  for (const GenericModifier& m : kGenericModifiers) {
    if (id == m.identifier) return &m;
  }
  return nullptr;
}

// honeybee-radiance's four generic modifier sets, by slot (the order of Slot). The first is
// the default of every room without a set of its own (generic_modifier_set_visible); its
// entries are also what a model's set leaves out (modifierset.py's _default_modifiers).
struct GenericSet {
  const char* identifier;
  const char* slots[kSlotCount];
};
#define FENESTRA_HB_OPENINGS(window, interior)                                              \
  window, window, window, interior, "generic_opaque_door_0.50", "generic_opaque_door_0.50", \
      "generic_exterior_window_vis_0.64", "generic_opaque_door_0.50",                       \
      "generic_interior_window_vis_0.88", "generic_exterior_shade_0.35",                    \
      "generic_interior_shade_0.50", "generic_context_0.20"
constexpr GenericSet kGenericSets[] = {
    {"Generic_Interior_Visible_Modifier_Set",
     {"generic_wall_0.50", "generic_wall_0.50", "generic_floor_0.20", "generic_floor_0.20",
      "generic_ceiling_0.80", "generic_ceiling_0.80",
      FENESTRA_HB_OPENINGS("generic_exterior_window_vis_0.64",
                           "generic_interior_window_vis_0.88")}},
    {"Generic_Interior_Solar_Modifier_Set",
     {"generic_wall_0.50", "generic_wall_0.50", "generic_floor_0.20", "generic_floor_0.20",
      "generic_ceiling_0.80", "generic_ceiling_0.80",
      FENESTRA_HB_OPENINGS("generic_exterior_window_sol_0.37",
                           "generic_interior_window_sol_0.77")}},
    {"Generic_Exterior_Visible_Modifier_Set",
     {"generic_wall_exterior_side_0.35", "generic_wall_0.50", "generic_floor_exterior_side_0.50",
      "generic_floor_0.20", "generic_ceiling_exterior_side_0.35", "generic_ceiling_0.80",
      FENESTRA_HB_OPENINGS("generic_exterior_window_vis_0.64",
                           "generic_interior_window_vis_0.88")}},
    {"Generic_Exterior_Solar_Modifier_Set",
     {"generic_wall_exterior_side_0.35", "generic_wall_0.50", "generic_floor_exterior_side_0.50",
      "generic_floor_0.20", "generic_ceiling_exterior_side_0.35", "generic_ceiling_0.80",
      FENESTRA_HB_OPENINGS("generic_exterior_window_sol_0.37",
                           "generic_interior_window_sol_0.77")}},
};
#undef FENESTRA_HB_OPENINGS
constexpr int kGenericSetCount = sizeof(kGenericSets) / sizeof(kGenericSets[0]);

// A modifier set's members: (sub-set, key) -> slot.
struct SetMember {
  const char* subset;
  const char* key;
  Slot slot;
};
constexpr SetMember kSetMembers[] = {
    {"wall_set", "exterior_modifier", Slot::kWallExterior},
    {"wall_set", "interior_modifier", Slot::kWallInterior},
    {"floor_set", "exterior_modifier", Slot::kFloorExterior},
    {"floor_set", "interior_modifier", Slot::kFloorInterior},
    {"roof_ceiling_set", "exterior_modifier", Slot::kRoofCeilingExterior},
    {"roof_ceiling_set", "interior_modifier", Slot::kRoofCeilingInterior},
    {"aperture_set", "window_modifier", Slot::kWindow},
    {"aperture_set", "skylight_modifier", Slot::kSkylight},
    {"aperture_set", "operable_modifier", Slot::kOperableWindow},
    {"aperture_set", "interior_modifier", Slot::kInteriorAperture},
    {"door_set", "exterior_modifier", Slot::kDoorExterior},
    {"door_set", "overhead_modifier", Slot::kDoorOverhead},
    {"door_set", "exterior_glass_modifier", Slot::kDoorExteriorGlass},
    {"door_set", "interior_modifier", Slot::kDoorInterior},
    {"door_set", "interior_glass_modifier", Slot::kDoorInteriorGlass},
    {"shade_set", "exterior_modifier", Slot::kShadeExterior},
    {"shade_set", "interior_modifier", Slot::kShadeInterior},
};

// The photopic luminance of a colour: its grey.
double Grey(double r, double g, double b) { return 0.265 * r + 0.670 * g + 0.065 * b; }

std::string Lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

// Member `key` of `m`, a number in [0, 1] (below 1 when `below_one`), `fallback` when absent.
absl::StatusOr<double> Fraction(const Json& m, const char* key, double fallback, bool below_one) {
  FENESTRA_ASSIGN_OR_RETURN(value, m.NumberOr(key, fallback));
  if (value >= 0 && (below_one ? value < 1 : value <= 1)) return value;
  FENESTRA_ASSIGN_OR_RETURN(field, m.Get(key));
  return field.Error(absl::StrCat("must be in [0, 1", below_one ? ")" : "]", ", got ", value));
}

// A glass of transmissivity `t` (grey) and index `index` as a scene material.
absl::StatusOr<v1::Material> GlassMaterial(double t, double index, const std::string& name,
                                           const Json& where) {
  const double normal =
      GlassPane{static_cast<float>(t), static_cast<float>(index)}.Transmittance(1.0f);
  if (!(normal > 0 && normal <= kMaxGlassNormalTransmittance)) {
    return where.Error(absl::StrCat("glass '", name, "' of transmissivity ", t, " lets through ",
                                    normal,
                                    " at normal incidence; a pane "
                                    "must let through more than 0 and at most ",
                                    kMaxGlassNormalTransmittance));
  }
  v1::Material m;
  m.set_name(name);
  m.mutable_glass()->set_transmittance(normal);
  return m;
}

}  // namespace

absl::StatusOr<Modifiers> Modifiers::Read(const std::optional<Json>& radiance) {
  Modifiers modifiers;
  if (!radiance) return modifiers;
  FENESTRA_ASSIGN_OR_RETURN(list, radiance->ListOf("modifiers", kMaxModifiers, "modifiers"));
  for (const Json& m : list) FENESTRA_RETURN_IF_ERROR(modifiers.ReadModifier(m));
  FENESTRA_ASSIGN_OR_RETURN(sets, radiance->ListOf("modifier_sets", kMaxModifiers, "sets"));
  for (const Json& s : sets) FENESTRA_RETURN_IF_ERROR(modifiers.ReadSet(s));
  return modifiers;
}

absl::Status Modifiers::ReadModifier(const Json& modifier) {
  FENESTRA_ASSIGN_OR_RETURN(identifier, modifier.Get("identifier"));
  FENESTRA_ASSIGN_OR_RETURN(id, Identifier(identifier));
  if (model_modifiers_.size() >= kMaxModifiers) {
    return modifier.Error(absl::StrCat("more than ", kMaxModifiers, " modifiers"));
  }
  const auto [it, added] = model_modifiers_.emplace(id, modifier);
  // The same modifier given twice is one (a model's list may repeat it)
  if (!added &&
      !google::protobuf::util::MessageDifferencer::Equals(it->second.value(), modifier.value())) {
    return identifier.Error(absl::StrCat("modifier '", id, "' is defined twice, differently"));
  }
  return absl::OkStatus();
}

absl::Status Modifiers::ReadSet(const Json& set) {
  FENESTRA_ASSIGN_OR_RETURN(identifier, set.Get("identifier"));
  FENESTRA_ASSIGN_OR_RETURN(id, Identifier(identifier));
  for (const Set& other : sets_) {
    if (other.identifier == id) {
      return identifier.Error(absl::StrCat("modifier set '", id, "' is defined twice"));
    }
  }
  Set entry;
  entry.identifier = id;
  for (const SetMember& member : kSetMembers) {
    FENESTRA_ASSIGN_OR_RETURN(subset, set.Find(member.subset));
    if (!subset) continue;
    FENESTRA_ASSIGN_OR_RETURN(value, subset->Find(member.key));
    if (!value) continue;
    if (value->value().kind_case() == google::protobuf::Value::kStructValue) {
      // A full ModifierSet holds its modifiers themselves
      FENESTRA_RETURN_IF_ERROR(ReadModifier(*value));
      FENESTRA_ASSIGN_OR_RETURN(inline_id, value->Get("identifier"));
      FENESTRA_ASSIGN_OR_RETURN(name, inline_id.String());
      entry.model[static_cast<int>(member.slot)] = name;
    } else {
      FENESTRA_ASSIGN_OR_RETURN(name, Identifier(*value));
      entry.model[static_cast<int>(member.slot)] = name;
    }
  }
  sets_.push_back(std::move(entry));
  return absl::OkStatus();
}

absl::StatusOr<int> Modifiers::RoomSet(const Json& room) const {
  FENESTRA_ASSIGN_OR_RETURN(properties, room.Find("properties"));
  if (!properties) return kGenericSet;
  FENESTRA_ASSIGN_OR_RETURN(radiance, properties->Find("radiance"));
  if (!radiance) return kGenericSet;
  FENESTRA_ASSIGN_OR_RETURN(field, radiance->Find("modifier_set"));
  if (!field) return kGenericSet;
  FENESTRA_ASSIGN_OR_RETURN(id, Identifier(*field));
  for (int i = 0; i < kGenericSetCount; ++i) {
    if (id == kGenericSets[i].identifier) return i;
  }
  for (size_t i = 0; i < sets_.size(); ++i) {
    if (sets_[i].identifier == id) return kGenericSetCount + static_cast<int>(i);
  }
  return field->Error(absl::StrCat("unknown modifier set '", id,
                                   "' (neither the model's nor one of honeybee-radiance's)"));
}

absl::StatusOr<Assigned> Modifiers::For(const Json& element, int set, Slot slot) {
  FENESTRA_ASSIGN_OR_RETURN(properties, element.Find("properties"));
  if (properties) {
    FENESTRA_ASSIGN_OR_RETURN(radiance, properties->Find("radiance"));
    if (radiance) {
      FENESTRA_ASSIGN_OR_RETURN(own, radiance->Find("modifier"));
      if (own) {
        FENESTRA_ASSIGN_OR_RETURN(id, Identifier(*own));
        return Use(id, false, *own);
      }
    }
  }
  const int s = static_cast<int>(slot);
  if (set >= kGenericSetCount) {
    const std::optional<std::string>& id =
        sets_[static_cast<size_t>(set - kGenericSetCount)].model[s];
    if (id) return Use(*id, false, element);
    set = kGenericSet;  // what a model's set leaves out
  }
  return Use(kGenericSets[set].slots[s], true, element);
}

absl::StatusOr<Assigned> Modifiers::Use(const std::string& id, bool generic, const Json& where) {
  const auto model = model_modifiers_.find(id);
  const GenericModifier* builtin = FindGeneric(id);
  generic = generic || model == model_modifiers_.end();
  const auto key = std::pair{id, generic};
  if (const auto it = used_.find(key); it != used_.end()) return it->second;
  if (id == "void") return used_[key] = Assigned{};
  absl::StatusOr<v1::Material> material;
  if (!generic) {
    FENESTRA_ASSIGN_OR_RETURN(kind, model->second.Get("type"));
    FENESTRA_ASSIGN_OR_RETURN(type, kind.String());
    if (Lower(type) == "void") return used_[key] = Assigned{};
    material = Build(model->second, id);
  } else if (builtin == nullptr) {
    return where.Error(absl::StrCat("unknown modifier '", id,
                                    "' (neither the model's nor one of honeybee-radiance's)"));
  } else {
    // A generic modifier keeps its name unless the model has one of that name too
    std::string name = id;
    while (model_modifiers_.count(name) > 0) absl::StrAppend(&name, " (honeybee-radiance)");
    if (builtin->glass) {
      material = GlassMaterial(builtin->value, 1.52, name, where);
    } else {
      v1::Material plastic;
      plastic.set_name(name);
      plastic.mutable_plastic()->set_reflectance(builtin->value);
      material = plastic;
    }
  }
  if (!material.ok()) return material.status();
  Assigned assigned{material->name(), material->has_glass()};
  materials_.push_back(*std::move(material));
  return used_[key] = assigned;
}

absl::StatusOr<v1::Material> Modifiers::Build(const Json& modifier, const std::string& name) {
  FENESTRA_ASSIGN_OR_RETURN(kind, modifier.Get("type"));
  FENESTRA_ASSIGN_OR_RETURN(given_type, kind.String());
  const std::string type = Lower(given_type);
  v1::Material m;
  m.set_name(name);
  if (type == "glass") {
    FENESTRA_ASSIGN_OR_RETURN(r, Fraction(modifier, "r_transmissivity", 0, false));
    FENESTRA_ASSIGN_OR_RETURN(g, Fraction(modifier, "g_transmissivity", 0, false));
    FENESTRA_ASSIGN_OR_RETURN(b, Fraction(modifier, "b_transmissivity", 0, false));
    FENESTRA_ASSIGN_OR_RETURN(index, modifier.NumberOr("refraction_index", 1.52));
    if (!(index > 1 && index <= 5)) {
      FENESTRA_ASSIGN_OR_RETURN(field, modifier.Get("refraction_index"));
      return field.Error(absl::StrCat("must be in (1, 5], got ", index));
    }
    return GlassMaterial(Grey(r, g, b), index, name, modifier);
  }
  if (type != "plastic" && type != "metal" && type != "trans") {
    return kind.Error(
        absl::StrCat("modifier type ", QuoteText(given_type),
                     " is not supported (Plastic, Metal, Trans, Glass and Void are)"));
  }
  FENESTRA_ASSIGN_OR_RETURN(r, Fraction(modifier, "r_reflectance", 0, false));
  FENESTRA_ASSIGN_OR_RETURN(g, Fraction(modifier, "g_reflectance", 0, false));
  FENESTRA_ASSIGN_OR_RETURN(b, Fraction(modifier, "b_reflectance", 0, false));
  RadianceParameters p;
  p.colour = Grey(r, g, b);
  FENESTRA_ASSIGN_OR_RETURN(specularity,
                            Fraction(modifier, "specularity", type == "metal" ? 0.9 : 0, true));
  FENESTRA_ASSIGN_OR_RETURN(roughness, Fraction(modifier, "roughness", 0, false));
  p.specularity = specularity;
  p.roughness = roughness;
  MaterialKind material_kind = MaterialKind::kPlastic;
  if (type == "plastic") {
    m.mutable_plastic()->set_reflectance(p.colour);
    m.mutable_plastic()->set_specularity(p.specularity);
    m.mutable_plastic()->set_roughness(p.roughness);
  } else if (type == "metal") {
    material_kind = MaterialKind::kMetal;
    m.mutable_metal()->set_reflectance(p.colour);
    m.mutable_metal()->set_specularity(p.specularity);
    m.mutable_metal()->set_roughness(p.roughness);
  } else {
    material_kind = MaterialKind::kTrans;
    FENESTRA_ASSIGN_OR_RETURN(diffuse, Fraction(modifier, "transmitted_diff", 0, false));
    FENESTRA_ASSIGN_OR_RETURN(specular, Fraction(modifier, "transmitted_spec", 0, false));
    p.transmissivity = diffuse;
    p.transmitted_specular = specular;
    v1::Material::Trans* t = m.mutable_trans();
    t->set_reflectance(p.colour);
    t->set_specularity(p.specularity);
    t->set_roughness(p.roughness);
    t->set_transmissivity(p.transmissivity);
    t->set_transmitted_specular(p.transmitted_specular);
  }
  if (const absl::Status parts = CheckMaterialParts(MaterialOfKind(material_kind, p));
      !parts.ok()) {
    return modifier.Error(
        absl::StrCat("as diffuse, specular and transmitted parts, ", parts.message()));
  }
  return m;
}

}  // namespace fenestra::hbjson
