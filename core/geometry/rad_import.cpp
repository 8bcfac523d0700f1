#include "core/geometry/rad_import.h"

#include <google/protobuf/struct.pb.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <optional>
#include <set>
#include <unordered_map>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/common/text.h"
#include "core/geometry/polygon_triangulate.h"
#include "core/geometry/rad_common.h"
#include "core/geometry/rad_geometry.h"
#include "core/geometry/rad_io.h"
#include "core/trace/glass.h"  // header-only: the pane's formulas, shared with the tracer

namespace fenestra {
namespace {

// Relative tolerance of a window's right angles, BuildScene's (scene.cpp).
constexpr double kRadRightAngleTolerance = 1e-6;

absl::Status RadError(absl::string_view file, int64_t line, absl::string_view reason) {
  return absl::InvalidArgumentError(absl::StrCat(file, ":", line, ": ", reason));
}

// A word of a Radiance text or a directive (the text after "#@fenestra "), with its line.
struct RadToken {
  enum Kind { kEnd, kWord, kDirective } kind = kEnd;
  absl::string_view text;
  int64_t line = 0;
};

// Splits a Radiance text into words and directives; other comments are dropped. A `#` that
// begins a word begins a comment; it is a directive when it is the first thing on its line.
class RadLexer {
 public:
  explicit RadLexer(absl::string_view text) : text_(text) {}

  RadToken Next() {
    while (at_ < text_.size()) {
      const char c = text_[at_];
      if (c == '\n') {
        ++line_;
        line_blank_ = true;
        ++at_;
        continue;
      }
      if (std::isspace(static_cast<unsigned char>(c))) {
        ++at_;
        continue;
      }
      if (c == '#') {
        const size_t end = std::min(text_.find('\n', at_), text_.size());
        absl::string_view comment = text_.substr(at_, end - at_);
        at_ = end;
        if (!line_blank_ || comment.substr(0, kRadDirective.size()) != kRadDirective) continue;
        comment.remove_prefix(kRadDirective.size());
        if (!comment.empty() && comment.back() == '\r') comment.remove_suffix(1);
        return {RadToken::kDirective, comment, line_};
      }
      const size_t start = at_;
      while (at_ < text_.size() && !std::isspace(static_cast<unsigned char>(text_[at_]))) ++at_;
      line_blank_ = false;
      return {RadToken::kWord, text_.substr(start, at_ - start), line_};
    }
    return {RadToken::kEnd, {}, line_};
  }

 private:
  absl::string_view text_;
  size_t at_ = 0;
  int64_t line_ = 1;
  bool line_blank_ = true;  // nothing but whitespace so far on the current line
};

// A window name from a polygon identifier: letters, digits, '_', '-' and '.' kept, every
// other byte '_', at most 64.
std::string RadWindowName(absl::string_view identifier) {
  std::string name(identifier.substr(0, 64));
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-' && c != '.') c = '_';
  }
  return name;
}

// `v` as a message, -0 made 0 (as protobuf's JSON writes it).
v1::Vec3 RadVec3(Vec3d v) {
  v1::Vec3 out;
  out.set_x(v.x + 0.0);
  out.set_y(v.y + 0.0);
  out.set_z(v.z + 0.0);
  return out;
}

// A window of Scene.windows and where it came from.
struct RadWindow {
  v1::Window window;
  std::string where;       // "FILE:LINE"
  std::string identifier;  // its glass polygon's, empty for a directive's window
};

// Reads the sources and the points file into a scene, one primitive or directive at a time.
class RadReader {
 public:
  RadReader(const RadImportOptions& options, RadImportSummary& summary)
      : options_(options), summary_(summary) {}

  absl::Status ReadPoints(const RadSource& points);
  absl::Status ReadSource(const RadSource& source);
  absl::StatusOr<v1::Scene> Finish(const std::vector<RadSource>& sources);

 private:
  // The directive or primitive under way and what follows it.
  absl::Status Directive(const RadToken& token);
  absl::Status SkipBlindGeometry(const RadToken& begin);
  absl::Status Primitive(const RadToken& modifier);
  absl::StatusOr<RadToken> Word(absl::string_view what);
  absl::StatusOr<int64_t> Count(absl::string_view what);
  absl::Status Material(absl::string_view type, absl::string_view modifier, absl::string_view id,
                        int64_t line);
  absl::Status Polygon(absl::string_view modifier, absl::string_view id, int64_t line);
  absl::Status Window(absl::string_view id, int material, const std::vector<Vec3d>& v,
                      const PolygonShape& shape, int64_t line);
  absl::Status Triangles(const std::string& name, int material, const std::vector<Vec3d>& v,
                         int64_t line);
  absl::Status AddSurface(const std::string& name, int material, const std::vector<Vec3d>& v,
                          int64_t line);
  absl::Status NameWindows();
  absl::Status TooManyWindows(int64_t line) const {
    return Error(line, absl::StrCat("a scene holds at most ", kMaxSceneWindows, " windows"));
  }
  std::string Where(int64_t line) const { return absl::StrCat(file_, ":", line); }
  absl::Status Error(int64_t line, absl::string_view reason) const {
    return RadError(file_, line, reason);
  }

  struct Modifier {
    int material = 0;  // index into scene_.materials
    bool glass = false;
    std::string where;
  };

  const RadImportOptions& options_;
  RadImportSummary& summary_;
  v1::Scene scene_;
  std::unordered_map<std::string, Modifier> modifiers_;  // by identifier
  std::set<std::string> material_names_;
  std::vector<RadWindow> windows_;
  std::vector<std::string> sensor_names_;
  std::string sensor_names_where_;  // the first `sensors` directive
  std::optional<std::string> scene_name_;
  bool site_given_ = false;
  Vec3d sensor_centroid_{0, 0, 0};
  int64_t primitives_ = 0, vertices_ = 0;
  std::vector<double> reals_;  // the real arguments of the primitive under way

  // The source under way
  std::string file_;
  RadLexer lexer_{""};
  v1::Side side_ = v1::SIDE_INDOOR;
  std::optional<std::string> surface_name_;  // a `surface` directive's, for the next polygon
  int64_t surface_line_ = 0;
  std::optional<v1::Material> material_;  // a `material` directive's, for the next material
  int64_t material_line_ = 0;
};

absl::Status RadReader::ReadPoints(const RadSource& points) {
  if (points.text.size() > options_.max_source_bytes) {
    return RadError(
        points.name, 1,
        absl::StrCat("the points file holds more than ", options_.max_source_bytes, " bytes"));
  }
  absl::string_view text = points.text;
  Vec3d sum{0, 0, 0};
  for (int64_t line = 1; !text.empty(); ++line) {
    const size_t end = std::min(text.find('\n'), text.size());
    absl::string_view rest = text.substr(0, end);
    text.remove_prefix(std::min(end + 1, text.size()));
    std::array<double, 6> values;
    int count = 0;
    for (;;) {
      while (!rest.empty() && std::isspace(static_cast<unsigned char>(rest.front()))) {
        rest.remove_prefix(1);
      }
      if (rest.empty() || (count == 0 && rest.front() == '#')) break;
      size_t length = 0;
      while (length < rest.size() && !std::isspace(static_cast<unsigned char>(rest[length]))) {
        ++length;
      }
      const absl::string_view word = rest.substr(0, length);
      rest.remove_prefix(length);
      if (count == 6) return RadError(points.name, line, "more than 6 numbers on a sensor's line");
      if (!absl::SimpleAtod(word, &values[count]) || !std::isfinite(values[count])) {
        return RadError(points.name, line,
                        absl::StrCat(QuoteText(word), " is not a finite number"));
      }
      ++count;
    }
    if (count == 0) continue;
    if (count != 6) {
      return RadError(points.name, line, "a sensor's line holds 6 numbers: x y z dx dy dz");
    }
    const Vec3d p{values[0], values[1], values[2]}, d{values[3], values[4], values[5]};
    for (const double c : {p.x, p.y, p.z}) {
      if (!(std::abs(c) <= kMaxCoordinateM)) {
        return RadError(points.name, line,
                        absl::StrCat("the sensor lies beyond ", kMaxCoordinateM,
                                     " m from the origin, the scene's bound"));
      }
    }
    if (d.x == 0 && d.y == 0 && d.z == 0) {
      return RadError(points.name, line, "the sensor's direction is zero");
    }
    if (scene_.sensors_size() >= kMaxSceneSensors) {
      return RadError(points.name, line,
                      absl::StrCat("a scene holds at most ", kMaxSceneSensors, " sensors"));
    }
    v1::Sensor* s = scene_.add_sensors();
    *s->mutable_position() = RadVec3(p);
    *s->mutable_direction() = RadVec3(d);
    sum += p;
  }
  if (scene_.sensors_size() > 0) sensor_centroid_ = sum / double(scene_.sensors_size());
  return absl::OkStatus();
}

absl::Status RadReader::ReadSource(const RadSource& source) {
  file_ = source.name;
  if (source.text.size() > options_.max_source_bytes) {
    return Error(1, absl::StrCat("the file holds more than ", options_.max_source_bytes,
                                 " bytes, the import's bound"));
  }
  lexer_ = RadLexer(source.text);
  side_ = source.outdoor ? v1::SIDE_OUTDOOR : v1::SIDE_INDOOR;
  surface_name_.reset();
  material_.reset();
  for (RadToken token = lexer_.Next(); token.kind != RadToken::kEnd; token = lexer_.Next()) {
    FENESTRA_RETURN_IF_ERROR(token.kind == RadToken::kDirective ? Directive(token)
                                                                : Primitive(token));
  }
  if (surface_name_) return Error(surface_line_, "the surface directive names no polygon");
  if (material_) return Error(material_line_, "the material directive describes no material");
  return absl::OkStatus();
}

absl::Status RadReader::Directive(const RadToken& token) {
  if (token.text.size() > kMaxRadDirectiveBytes) {
    return Error(token.line,
                 absl::StrCat("a directive holds at most ", kMaxRadDirectiveBytes, " bytes"));
  }
  if (token.text == kRadBlindBegin) return SkipBlindGeometry(token);
  if (token.text == kRadBlindEnd) return Error(token.line, "blind-geometry end without begin");
  const size_t space = std::min(token.text.find(' '), token.text.size());
  const absl::string_view keyword = token.text.substr(0, space);
  const absl::string_view argument = token.text.substr(std::min(space + 1, token.text.size()));
  const auto name = [&](absl::string_view what) -> absl::StatusOr<std::string> {
    if (absl::Status text = CheckText(argument, what); !text.ok()) {
      return Error(token.line, text.message());
    }
    return std::string(argument);
  };
  const auto json = [&](google::protobuf::Message* message) -> absl::Status {
    if (absl::Status parsed = ParseRadJson(argument, message); !parsed.ok()) {
      return Error(token.line, absl::StrCat("malformed ", keyword, " JSON: ", parsed.message()));
    }
    return absl::OkStatus();
  };
  if (keyword == "scene") {
    if (scene_name_) return Error(token.line, "the scene is named twice");
    FENESTRA_ASSIGN_OR_RETURN(scene_name, name("the scene's name"));
    scene_name_ = scene_name;
  } else if (keyword == "side") {
    if (argument != "indoor" && argument != "outdoor") {
      return Error(token.line, "the side is indoor or outdoor");
    }
    side_ = argument == "indoor" ? v1::SIDE_INDOOR : v1::SIDE_OUTDOOR;
  } else if (keyword == "surface") {
    if (surface_name_) return Error(token.line, "a surface directive follows another");
    FENESTRA_ASSIGN_OR_RETURN(surface, name("the surface's name"));
    surface_name_ = surface;
    surface_line_ = token.line;
  } else if (keyword == "material") {
    if (material_) return Error(token.line, "a material directive follows another");
    material_.emplace();
    material_line_ = token.line;
    return json(&*material_);
  } else if (keyword == "window") {
    if (windows_.size() >= kMaxSceneWindows) return TooManyWindows(token.line);
    RadWindow& w = windows_.emplace_back();
    w.where = Where(token.line);
    return json(&w.window);
  } else if (keyword == "site") {
    if (site_given_) return Error(token.line, "the site is given twice");
    site_given_ = true;
    FENESTRA_RETURN_IF_ERROR(json(scene_.mutable_site()));
    v1::Scene part;
    *part.mutable_site() = scene_.site();
    return BuildRadPart(part, Where(token.line)).status();
  } else if (keyword == "sensors") {
    google::protobuf::ListValue list;
    FENESTRA_RETURN_IF_ERROR(json(&list));
    if (sensor_names_where_.empty()) sensor_names_where_ = Where(token.line);
    if (static_cast<int64_t>(sensor_names_.size()) + list.values_size() > kMaxSceneSensors) {
      return Error(token.line,
                   absl::StrCat("a scene holds at most ", kMaxSceneSensors, " sensors"));
    }
    for (const google::protobuf::Value& value : list.values()) {
      if (value.kind_case() != google::protobuf::Value::kStringValue) {
        return Error(token.line, "sensor names are JSON strings");
      }
      if (absl::Status text = CheckText(value.string_value(), "a sensor's name"); !text.ok()) {
        return Error(token.line, text.message());
      }
      sensor_names_.push_back(value.string_value());
    }
  } else {
    return Error(token.line, absl::StrCat("unknown directive ", QuoteText(keyword)));
  }
  return absl::OkStatus();
}

// Skips the slats an export wrote for Radiance: the blind comes from its window's JSON.
absl::Status RadReader::SkipBlindGeometry(const RadToken& begin) {
  for (RadToken token = lexer_.Next(); token.kind != RadToken::kEnd; token = lexer_.Next()) {
    if (token.kind != RadToken::kDirective) continue;
    if (token.text == kRadBlindEnd) return absl::OkStatus();
    if (token.text == kRadBlindBegin) {
      return Error(token.line, "a blind-geometry block inside another");
    }
  }
  return Error(begin.line, "the blind-geometry block has no end");
}

absl::StatusOr<RadToken> RadReader::Word(absl::string_view what) {
  const RadToken token = lexer_.Next();
  if (token.kind == RadToken::kWord) return token;
  return Error(token.line,
               absl::StrCat(token.kind == RadToken::kEnd ? "the file ends" : "a directive comes",
                            " before ", what));
}

absl::StatusOr<int64_t> RadReader::Count(absl::string_view what) {
  FENESTRA_ASSIGN_OR_RETURN(token, Word(what));
  int64_t count = 0;
  if (!absl::SimpleAtoi(token.text, &count) || count < 0) {
    return Error(token.line, absl::StrCat(QuoteText(token.text), " is not a count of ", what));
  }
  return count;
}

absl::Status RadReader::Primitive(const RadToken& modifier) {
  const absl::string_view mod = modifier.text;
  if (mod.front() == '!') {
    return Error(modifier.line,
                 absl::StrCat("unsupported primitive ", QuoteText(mod), " (commands are not run)"));
  }
  FENESTRA_ASSIGN_OR_RETURN(type, Word("the primitive's type"));
  const bool polygon = type.text == "polygon";
  if (!polygon && type.text != "plastic" && type.text != "metal" && type.text != "trans" &&
      type.text != "glass") {
    return Error(type.line, absl::StrCat("unsupported primitive ", QuoteText(type.text)));
  }
  FENESTRA_ASSIGN_OR_RETURN(id, Word("the primitive's identifier"));
  const std::string what = absl::StrCat(type.text, " ", QuoteText(id.text));
  if (++primitives_ > options_.max_primitives) {
    return Error(id.line, absl::StrCat("more than ", options_.max_primitives,
                                       " primitives, the import's bound"));
  }
  // Arguments: no strings, no integers, the reals each type takes
  for (const char* kind : {"string", "integer"}) {
    FENESTRA_ASSIGN_OR_RETURN(count, Count(absl::StrCat(what, "'s ", kind, " arguments")));
    if (count != 0) {
      return Error(modifier.line,
                   absl::StrCat(what, " takes no ", kind, " arguments, got ", count));
    }
  }
  FENESTRA_ASSIGN_OR_RETURN(reals, Count(what + "'s real arguments"));
  if (polygon) {
    if (reals % 3 != 0 || reals < 9 || reals / 3 > options_.max_polygon_vertices) {
      return Error(modifier.line,
                   absl::StrCat(what, " takes 3 real arguments per vertex, 3 to ",
                                options_.max_polygon_vertices, " vertices, got ", reals));
    }
    if ((vertices_ += reals / 3) > options_.max_vertices) {
      return Error(modifier.line, absl::StrCat("more than ", options_.max_vertices,
                                               " polygon vertices, the import's bound"));
    }
  } else {
    const int64_t wanted = type.text == "trans" ? 7 : type.text == "glass" ? 3 : 5;
    if (reals != wanted && !(type.text == "glass" && reals == 4)) {
      return Error(modifier.line,
                   absl::StrCat(what, " takes ", wanted, type.text == "glass" ? " or 4" : "",
                                " real arguments, got ", reals));
    }
  }
  reals_.clear();
  reals_.reserve(reals);
  for (int64_t i = 0; i < reals; ++i) {
    FENESTRA_ASSIGN_OR_RETURN(word, Word(what + "'s real arguments"));
    double value = 0;
    if (!absl::SimpleAtod(word.text, &value) || !std::isfinite(value)) {
      return Error(word.line, absl::StrCat("real argument ", i + 1, " of ", what, ", ",
                                           QuoteText(word.text), ", is not a finite number"));
    }
    reals_.push_back(value + 0.0);  // -0 as 0
  }
  if (polygon) return Polygon(mod, id.text, modifier.line);
  return Material(type.text, mod, id.text, modifier.line);
}

absl::Status RadReader::Material(absl::string_view type, absl::string_view modifier,
                                 absl::string_view id, int64_t line) {
  const std::string what = absl::StrCat(type, " ", QuoteText(id));
  if (surface_name_) return Error(surface_line_, "the surface directive names no polygon");
  if (modifier != "void") {
    return Error(line, absl::StrCat(what,
                                    ": a material's modifier must be void (patterns, "
                                    "textures and mixtures are not supported)"));
  }
  if (id == "void") return Error(line, "a modifier cannot be named void");
  const std::string identifier(id);
  if (auto it = modifiers_.find(identifier); it != modifiers_.end()) {
    return Error(line, absl::StrCat("modifier ", QuoteText(id), " is defined twice (first at ",
                                    it->second.where, ")"));
  }
  const std::vector<double>& r = reals_;
  v1::Material m;
  m.set_name(identifier);
  const double colour = RadLuminance(r[0], r[1], r[2]);
  if (type == "glass") {
    if (r.size() == 4 && std::abs(r[3] - 1.52) > 1e-9) {
      return Error(line, absl::StrCat(what, ": index of refraction ", r[3],
                                      "; Fenestra's glass has 1.52 (trans or plastic make other "
                                      "glazing)"));
    }
    m.mutable_glass()->set_transmittance(GlassPane::NormalTransmittance(colour));
  } else {
    auto set = [&](auto* kind) {
      kind->set_reflectance(colour);
      kind->set_specularity(r[3]);
      kind->set_roughness(r[4]);
    };
    if (type == "plastic") set(m.mutable_plastic());
    if (type == "metal") set(m.mutable_metal());
    if (type == "trans") {
      set(m.mutable_trans());
      m.mutable_trans()->set_transmissivity(r[5]);
      m.mutable_trans()->set_transmitted_specular(r[6]);
    }
  }
  const bool directive = material_.has_value();
  if (directive) m = *std::exchange(material_, std::nullopt);
  v1::Scene part;
  *part.add_materials() = m;
  FENESTRA_ASSIGN_OR_RETURN(built, BuildRadPart(part, Where(line), "materials[0]",
                                                absl::StrCat(type, " ", QuoteText(m.name()))));
  // A directive's material is the one Radiance's arguments describe (within rounding)
  const RadianceModifier expected = RadianceModifierOf(built.materials[0]);
  bool same = type == expected.type && r.size() >= expected.reals.size();
  for (size_t i = 0; directive && same && i < expected.reals.size(); ++i) {
    const double scale = std::max({1.0, std::abs(r[i]), std::abs(expected.reals[i])});
    same = std::abs(r[i] - expected.reals[i]) <= 1e-6 * scale;
  }
  if (directive && !same) {
    return Error(material_line_, absl::StrCat("the material directive's ", expected.type,
                                              " does not match ", what, " that follows it"));
  }
  if (!material_names_.insert(m.name()).second) {
    return Error(line, absl::StrCat("material ", QuoteText(m.name()), " is defined twice"));
  }
  modifiers_[identifier] = {scene_.materials_size(), m.has_glass(), Where(line)};
  *scene_.add_materials() = std::move(m);
  ++summary_.materials;
  return absl::OkStatus();
}

absl::Status RadReader::Polygon(absl::string_view modifier, absl::string_view id, int64_t line) {
  ++summary_.polygons;
  const std::optional<std::string> named = std::exchange(surface_name_, std::nullopt);
  if (material_) return Error(material_line_, "the material directive describes no material");
  if (modifier == "void") {
    ++summary_.void_polygons;
    return absl::OkStatus();
  }
  const auto it = modifiers_.find(std::string(modifier));
  if (it == modifiers_.end()) {
    return Error(line, absl::StrCat("modifier ", QuoteText(modifier), " of polygon ", QuoteText(id),
                                    " is not defined before it"));
  }
  std::vector<Vec3d> v(reals_.size() / 3);
  for (size_t k = 0; k < v.size(); ++k) {
    v[k] = {reals_[3 * k], reals_[3 * k + 1], reals_[3 * k + 2]};
    for (const double c : {v[k].x, v[k].y, v[k].z}) {
      if (!(std::abs(c) <= kMaxCoordinateM)) {
        return Error(line,
                     absl::StrCat("vertex ", k + 1, " of polygon ", QuoteText(id), " lies beyond ",
                                  kMaxCoordinateM, " m from the origin, the scene's bound"));
      }
    }
  }
  const PolygonShape shape = ShapeOfPolygon(v);
  if (!shape.area) return Error(line, absl::StrCat("zero-area polygon ", QuoteText(id)));
  if (!shape.planar) return Error(line, absl::StrCat("polygon ", QuoteText(id), " is not planar"));
  const Modifier& m = it->second;
  if (m.glass && !named && side_ == v1::SIDE_INDOOR) return Window(id, m.material, v, shape, line);
  const std::string name = named ? *named : std::string(id);
  if (shape.convex) return AddSurface(name, m.material, v, line);
  return Triangles(name, m.material, v, line);
}

// A glass rectangle on the indoor side: the window (the opening) and its glazing, 1 mm in.
absl::Status RadReader::Window(absl::string_view id, int material, const std::vector<Vec3d>& v,
                               const PolygonShape& shape, int64_t line) {
  const std::string what =
      absl::StrCat("windows must be rectangles: glass polygon ", QuoteText(id));
  if (v.size() != 4) return Error(line, absl::StrCat(what, " has ", v.size(), " vertices"));
  for (size_t k = 0; k < 4; ++k) {
    const Vec3d a = v[(k + 1) % 4] - v[k], b = v[(k + 2) % 4] - v[(k + 1) % 4];
    if (std::abs(Dot(a, b)) > kRadRightAngleTolerance * Length(a) * Length(b)) {
      return Error(line, absl::StrCat(what, " is not right-angled at vertex ", (k + 1) % 4 + 1));
    }
  }
  const Vec3d* inside = scene_.sensors_size() > 0 ? &sensor_centroid_ : nullptr;
  const RadRectangle r = RadRectangleOf(v, shape.normal, inside);
  if (windows_.size() >= kMaxSceneWindows) return TooManyWindows(line);
  RadWindow& w = windows_.emplace_back();
  w.where = Where(line);
  w.identifier = std::string(id);
  *w.window.mutable_center() = RadVec3(r.center);
  *w.window.mutable_outward_normal() = RadVec3(r.normal);
  *w.window.mutable_up() = RadVec3(r.up);
  w.window.set_width_m(r.width_m);
  w.window.set_height_m(r.height_m);
  ++summary_.windows;
  std::vector<Vec3d> glazing = v;
  for (Vec3d& p : glazing) p = p - kRadGlazingInsetM * r.normal;
  const PolygonShape moved = ShapeOfPolygon(glazing);
  if (!moved.area || !moved.planar || !moved.convex) {
    return Error(line, absl::StrCat("the glazing of window ", QuoteText(id),
                                    " is not a polygon BuildScene takes"));
  }
  return AddSurface(std::string(id), material, glazing, line);
}

// A non-convex planar polygon as triangles: zero-area ones (along a seam) are left out.
absl::Status RadReader::Triangles(const std::string& name, int material,
                                  const std::vector<Vec3d>& v, int64_t line) {
  const RadRings rings = SplitRadSeams(v);
  absl::StatusOr<std::vector<std::array<Vec3d, 3>>> triangles =
      TriangulatePlanarPolygon(rings.outline, rings.holes);
  if (!triangles.ok()) {
    return Error(line,
                 absl::StrCat("non-convex polygon ", QuoteText(name),
                              " cannot be split into triangles: ", triangles.status().message()));
  }
  ++summary_.triangulated_polygons;
  int k = 0;
  for (const std::array<Vec3d, 3>& t : *triangles) {
    const std::vector<Vec3d> corners(t.begin(), t.end());
    const PolygonShape shape = ShapeOfPolygon(corners);
    if (!shape.area || !shape.planar || !shape.convex) {
      ++summary_.dropped_triangles;
      continue;
    }
    FENESTRA_RETURN_IF_ERROR(AddSurface(absl::StrCat(name, "#", k++), material, corners, line));
  }
  return absl::OkStatus();
}

absl::Status RadReader::AddSurface(const std::string& name, int material,
                                   const std::vector<Vec3d>& v, int64_t line) {
  if (absl::Status text = CheckText(name, "the surface's name"); !text.ok()) {
    return Error(line, text.message());
  }
  v1::Surface* s = scene_.add_surfaces();
  s->set_name(name);
  s->set_material(scene_.materials(material).name());
  s->set_side(side_);
  for (const Vec3d& p : v) *s->mutable_polygon()->add_vertices() = RadVec3(p);
  return absl::OkStatus();
}

// Names the windows made of glass polygons (unique among all), and checks every window as
// BuildScene does.
absl::Status RadReader::NameWindows() {
  std::set<std::string> taken;
  for (const RadWindow& w : windows_) {
    if (!w.identifier.empty() || w.window.name().empty()) continue;
    if (!taken.insert(w.window.name()).second) {
      return absl::InvalidArgumentError(
          absl::StrCat(w.where, ": window name ", QuoteText(w.window.name()), " is given twice"));
    }
  }
  for (RadWindow& w : windows_) {
    if (w.identifier.empty()) continue;
    const std::string base = RadWindowName(w.identifier);
    std::string name = base;
    for (int n = 2; !taken.insert(name).second; ++n) {
      const std::string suffix = absl::StrCat("_", n);
      name = base.substr(0, 64 - suffix.size()) + suffix;
    }
    w.window.set_name(name);
  }
  v1::Scene part;
  *part.mutable_materials() = scene_.materials();
  for (const RadWindow& w : windows_) {
    *part.mutable_windows()->Add() = w.window;
    FENESTRA_RETURN_IF_ERROR(BuildRadPart(part, w.where, "windows[0]",
                                          absl::StrCat("window ", QuoteText(w.window.name())))
                                 .status());
    part.clear_windows();
    *scene_.add_windows() = w.window;
  }
  // Together (names, blinds of one group), the last window named as the one that does not fit
  if (windows_.size() < 2) return absl::OkStatus();
  *part.mutable_windows() = scene_.windows();
  return BuildRadPart(part, windows_.back().where).status();
}

absl::StatusOr<v1::Scene> RadReader::Finish(const std::vector<RadSource>& sources) {
  FENESTRA_RETURN_IF_ERROR(NameWindows());
  if (!sensor_names_where_.empty() &&
      static_cast<int64_t>(sensor_names_.size()) != scene_.sensors_size()) {
    return absl::InvalidArgumentError(absl::StrCat(sensor_names_where_, ": ", sensor_names_.size(),
                                                   " sensor names for ", scene_.sensors_size(),
                                                   " sensors in the points file"));
  }
  for (int i = 0; i < scene_.sensors_size(); ++i) {
    scene_.mutable_sensors(i)->set_name(sensor_names_where_.empty() ? absl::StrCat("sensor_", i)
                                                                    : sensor_names_[i]);
  }
  if (scene_name_) {
    scene_.set_name(*scene_name_);
  } else if (!sources.empty()) {
    const std::string stem = std::filesystem::path(sources[0].name).stem().string();
    if (CheckText(stem, "name").ok()) scene_.set_name(stem);
  }
  return std::move(scene_);
}

}  // namespace

std::string DescribeRadImport(const RadImportSummary& summary, int64_t surfaces) {
  std::string line = absl::StrCat(summary.polygons, " polygons (", summary.windows,
                                  summary.windows == 1 ? " window" : " windows");
  if (summary.triangulated_polygons > 0) {
    absl::StrAppend(&line, ", ", summary.triangulated_polygons, " non-convex split into triangles");
  }
  absl::StrAppend(&line, ") as ", surfaces, " surfaces, ", summary.materials, " materials");
  if (summary.void_polygons > 0) {
    absl::StrAppend(&line, "; ", summary.void_polygons, " void polygons skipped");
  }
  if (summary.dropped_triangles > 0) {
    absl::StrAppend(&line, "; ", summary.dropped_triangles, " zero-area triangles left out");
  }
  return line;
}

absl::StatusOr<v1::Scene> ImportRadiance(const std::vector<RadSource>& sources,
                                         const RadSource& points, const RadImportOptions& options,
                                         RadImportSummary* summary) {
  RadImportSummary counts;
  RadReader reader(options, counts);
  // The sensors first: a window's outward normal points away from them
  FENESTRA_RETURN_IF_ERROR(reader.ReadPoints(points));
  for (const RadSource& source : sources) FENESTRA_RETURN_IF_ERROR(reader.ReadSource(source));
  FENESTRA_ASSIGN_OR_RETURN(scene, reader.Finish(sources));
  if (summary) *summary = counts;
  return scene;
}

}  // namespace fenestra
