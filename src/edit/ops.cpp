// The ops file of `subvec edit` (edit/ops.h; format in docs/editing.md): a strict JSON reader and
// the application of each operation through the shape, color and selection tools.
#include "subvec/edit/ops.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>

#include "core/messages_p.h"
#include "io/json_p.h"
#include "subvec/core/error.h"
#include "subvec/edit/color.h"
#include "subvec/edit/objects.h"
#include "subvec/edit/selection.h"
#include "subvec/edit/shape.h"
#include "subvec/mesh/validate.h"

namespace subvec {
namespace {

using detail::num;

using Json = nlohmann::json;

constexpr int kMaxDepth = 16;
constexpr size_t kMaxDrawnPoints = 100000;  // add-feature's polyline

std::string point(Vec2 p) { return "[" + num(p.x) + ", " + num(p.y) + "]"; }

// Messages are one line: control characters become \xNN, long texts are cut.
std::string printable(const std::string& s, size_t max = 60) {
  std::string out;
  for (size_t i = 0; i < s.size() && i < max; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c < 0x20 || c == 0x7F) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    } else {
      out += s[i];
    }
  }
  return s.size() > max ? out + "..." : out;
}

// Where a message points: "ops[2] (drag)" and a key.
struct Place {
  size_t index = 0;
  std::string op;  // empty until known

  std::string str() const {
    return "ops[" + std::to_string(index) + "]" + (op.empty() ? "" : " (" + op + ")");
  }
  [[noreturn]] void fail(const std::string& message) const {
    throw Error(ErrorCode::kBadFile, str() + ": " + message);
  }
  [[noreturn]] void fail(const char* key, const std::string& message) const {
    fail(std::string("\"") + key + "\": " + message);
  }
};

const char* type_name(const Json& j) { return detail::json_type_name(j); }

double number(const Json& j, const Place& at, const char* key) {
  if (!j.is_number()) at.fail(key, std::string("expected a number, got ") + type_name(j));
  const double v = j.get<double>();
  if (!std::isfinite(v)) at.fail(key, "the number is not finite");
  return v;
}

Vec2 vec2(const Json& j, const Place& at, const char* key) {
  if (!j.is_array() || j.size() != 2 || !j[0].is_number() || !j[1].is_number()) {
    at.fail(key, std::string("expected [x, y] (two numbers), got ") +
                     (j.is_array() ? "an array of " + std::to_string(j.size()) + " elements"
                                   : type_name(j)));
  }
  return {number(j[0], at, key), number(j[1], at, key)};
}

Color color(const Json& j, const Place& at, const char* key) {
  if (!j.is_array() || j.size() != 3 || !j[0].is_number() || !j[1].is_number() ||
      !j[2].is_number()) {
    at.fail(key, std::string("expected [r, g, b] (three numbers, 0 to 255), got ") +
                     (j.is_array() ? "an array of " + std::to_string(j.size()) + " elements"
                                   : type_name(j)));
  }
  float c[3];
  for (int k = 0; k < 3; ++k) {
    const double v = number(j[k], at, key);
    if (v < 0 || v > 255) at.fail(key, "channel " + num(v) + " is outside 0 to 255");
    c[k] = static_cast<float>(v);
  }
  return {c[0], c[1], c[2]};
}

std::string string_value(const Json& j, const Place& at, const char* key) {
  if (!j.is_string()) at.fail(key, std::string("expected a string, got ") + type_name(j));
  return j.get<std::string>();
}

// The parsed operation object: required and optional keys, each key used once, the rest rejected.
class Fields {
 public:
  Fields(const Json& object, Place& at) : object_(object), at_(at) {}

  const Json& required(const char* key) {
    const Json* j = optional(key);
    if (!j) at_.fail(std::string("missing key \"") + key + "\"");
    return *j;
  }
  const Json* optional(const char* key) {
    allowed_.insert(key);
    auto it = object_.find(key);
    return it == object_.end() ? nullptr : &*it;
  }
  // After all keys were asked for: rejects the others.
  void finish() const {
    for (const auto& [key, value] : object_.items()) {
      if (allowed_.count(key)) continue;
      std::string list;
      for (const std::string& a : allowed_) list += (list.empty() ? "" : ", ") + a;
      at_.fail("unknown key \"" + printable(key) + "\" (expected one of: " + list + ")");
    }
  }

 private:
  const Json& object_;
  Place& at_;
  std::set<std::string> allowed_;
};

EditOp parse_op(const Json& j, Place& at) {
  if (!j.is_object()) at.fail(std::string("expected an operation object, got ") + type_name(j));
  Fields fields(j, at);
  EditOp op;
  const std::string kind = string_value(fields.required("op"), at, "op");
  if (kind == "drag") {
    op.kind = EditOp::Kind::kDrag;
  } else if (kind == "move-feature") {
    op.kind = EditOp::Kind::kMoveFeature;
  } else if (kind == "color") {
    op.kind = EditOp::Kind::kColor;
  } else if (kind == "move-vertices") {
    op.kind = EditOp::Kind::kMoveVertices;
  } else if (kind == "add-feature") {
    op.kind = EditOp::Kind::kAddFeature;
  } else if (kind == "delete-feature") {
    op.kind = EditOp::Kind::kDeleteFeature;
  } else if (kind == "make-object") {
    op.kind = EditOp::Kind::kMakeObject;
  } else if (kind == "move-object") {
    op.kind = EditOp::Kind::kMoveObject;
  } else if (kind == "hide-object") {
    op.kind = EditOp::Kind::kHideObject;
  } else if (kind == "show-object") {
    op.kind = EditOp::Kind::kShowObject;
  } else if (kind == "order-object") {
    op.kind = EditOp::Kind::kOrderObject;
  } else {
    at.fail("unknown op \"" + printable(kind) +
            "\" (expected drag, move-feature, color, move-vertices, add-feature, delete-feature, "
            "make-object, move-object, hide-object, show-object or order-object)");
  }
  at.op = kind;

  if (const Json* level = fields.optional("level")) {
    if (!level->is_number_integer() || level->get<int64_t>() < 0 ||
        level->get<int64_t>() >= Limits::kMaxLevels) {
      at.fail("level", "expected a level number, 0 to " + std::to_string(Limits::kMaxLevels - 1) +
                           ", got " + (level->is_number() ? level->dump() : type_name(*level)));
    }
    op.level = static_cast<int>(level->get<int64_t>());
  }
  // Drags grab a vertex or a feature; color edits may also fill a region or take listed vertices.
  auto select = [&](bool region_too) {
    if (const Json* s = fields.optional("select")) {
      const std::string v = string_value(*s, at, "select");
      const std::optional<EditSelect> e = edit_select_from_name(v);
      if (e && (region_too || drag_grabs(*e))) return *e;
      at.fail("select", "expected " +
                            std::string(region_too ? kEditSelectNames : kDragSelectNames) +
                            ", got \"" + printable(v) + "\"");
    }
    return EditSelect::kVertex;
  };

  // Inside an object (its own mesh) instead of the level's.
  auto in_object = [&]() {
    if (const Json* o = fields.optional("object")) {
      if (!o->is_number_integer() || o->get<int64_t>() < 0 || o->get<int64_t>() >= Limits::kMaxObjects) {
        at.fail("object", "expected an object index, 0 to " + std::to_string(Limits::kMaxObjects - 1) +
                              ", got " + (o->is_number() ? o->dump() : type_name(*o)));
      }
      op.in_object = true;
      op.object = static_cast<int>(o->get<int64_t>());
    }
  };
  auto region = [&]() {
    if (const Json* r = fields.optional("region")) {
      op.region = number(*r, at, "region");
      if (!(op.region > 0)) at.fail("region", "expected a positive number, got " + num(op.region));
    }
  };
  // A list of control vertex indices: non-empty, each once.
  auto vertex_list = [&]() {
    const Json& list = fields.required("vertices");
    if (!list.is_array() || list.empty()) {
      at.fail("vertices", std::string("expected a non-empty array of vertex indices, got ") +
                              (list.is_array() ? "an empty array" : type_name(list)));
    }
    std::set<int64_t> seen;
    for (const Json& v : list) {
      if (!v.is_number_integer() || v.get<int64_t>() < 0 || v.get<int64_t>() > std::numeric_limits<int32_t>::max()) {
        at.fail("vertices", "expected vertex indices (integers >= 0), got " +
                                (v.is_number() ? v.dump() : type_name(v)));
      }
      if (!seen.insert(v.get<int64_t>()).second) at.fail("vertices", "vertex " + v.dump() + " is listed twice");
      op.vertices.push_back(static_cast<int32_t>(v.get<int64_t>()));
    }
  };
  // An object index, or a position in the drawing order.
  auto index = [&](const char* key) {
    const Json& value = fields.required(key);
    if (!value.is_number_integer() || value.get<int64_t>() < 0 || value.get<int64_t>() >= Limits::kMaxObjects) {
      at.fail(key, "expected an object index, 0 to " + std::to_string(Limits::kMaxObjects - 1) + ", got " +
                       (value.is_number() ? value.dump() : type_name(value)));
    }
    return static_cast<int>(value.get<int64_t>());
  };
  switch (op.kind) {
    case EditOp::Kind::kMakeObject: {
      const Json* point = fields.optional("at");
      const Json* rect = fields.optional("rect");
      if ((point != nullptr) == (rect != nullptr)) at.fail("give \"at\" or \"rect\" (one of them)");
      if (point) op.at = vec2(*point, at, "at");
      if (rect) {
        std::array<int, 4> r{};
        const bool four = rect->is_array() && rect->size() == 4;
        for (size_t k = 0; four && k < 4; ++k) {
          const Json& v = (*rect)[k];
          if (!v.is_number_integer() || v.get<int64_t>() < 0 || v.get<int64_t>() > Limits::kMaxDimension) {
            at.fail("rect", "expected [x, y, width, height] (whole pixels, 0 to " +
                                std::to_string(Limits::kMaxDimension) + "), got " + v.dump());
          }
          r[k] = static_cast<int>(v.get<int64_t>());
        }
        if (!four) at.fail("rect", std::string("expected [x, y, width, height], got ") + type_name(*rect));
        op.rect = r;
      }
      if (const Json* n = fields.optional("name")) op.object_name = string_value(*n, at, "name");
      break;
    }
    case EditOp::Kind::kMoveObject: {
      op.object = index("object");
      const Json* translate = fields.optional("translate");
      const Json* rotate = fields.optional("rotate");
      const Json* scale = fields.optional("scale");
      if (!translate && !rotate && !scale) {
        at.fail("missing key \"translate\", \"rotate\" or \"scale\" (give one or more)");
      }
      if (translate) op.translate = vec2(*translate, at, "translate");
      if (rotate) op.rotate = number(*rotate, at, "rotate");
      if (scale) {
        op.scale = number(*scale, at, "scale");
        if (!(op.scale > 0)) at.fail("scale", "expected a positive number, got " + num(op.scale));
      }
      if (const Json* p = fields.optional("pivot")) op.pivot = vec2(*p, at, "pivot");
      break;
    }
    case EditOp::Kind::kHideObject:
    case EditOp::Kind::kShowObject:
      op.object = index("object");
      break;
    case EditOp::Kind::kOrderObject:
      op.object = index("object");
      op.position = index("to");
      break;
    case EditOp::Kind::kAddFeature: {
      const Json& list = fields.required("points");
      if (!list.is_array() || list.size() < 2) {
        at.fail("points", std::string("expected an array of at least 2 points [x, y], got ") +
                              (list.is_array() ? "an array of " + std::to_string(list.size()) + " elements"
                                               : type_name(list)));
      }
      if (list.size() > kMaxDrawnPoints) {
        at.fail("points", "more than " + std::to_string(kMaxDrawnPoints) + " points");
      }
      for (const Json& p : list) op.points.push_back(vec2(p, at, "points"));
      if (const Json* k = fields.optional("kind")) {
        const std::string v = string_value(*k, at, "kind");
        if (v == "tear") {
          op.feature_kind = FeatureKind::kTear;
        } else if (v == "crease") {
          op.feature_kind = FeatureKind::kCrease;
        } else {
          at.fail("kind", "expected \"tear\" or \"crease\", got \"" + printable(v) + "\"");
        }
      }
      break;
    }
    case EditOp::Kind::kDeleteFeature:
      op.select = EditSelect::kFeature;
      op.at = vec2(fields.required("at"), at, "at");
      break;
    case EditOp::Kind::kMoveVertices:
      in_object();
      region();
      vertex_list();
      op.translate = vec2(fields.required("translate"), at, "translate");
      break;
    case EditOp::Kind::kDrag:
      in_object();
      region();
      op.select = select(false);
      op.from = vec2(fields.required("from"), at, "from");
      op.to = vec2(fields.required("to"), at, "to");
      if (op.select == EditSelect::kFeature) {
        if (const Json* s = fields.optional("sigma")) {
          op.sigma = number(*s, at, "sigma");
          if (!(op.sigma > 0)) at.fail("sigma", "expected a positive number, got " + num(op.sigma));
        }
      }
      break;
    case EditOp::Kind::kMoveFeature: {
      in_object();
      region();
      op.select = EditSelect::kFeature;
      op.at = vec2(fields.required("at"), at, "at");
      const Json* translate = fields.optional("translate");
      const Json* rotate = fields.optional("rotate");
      if (!translate && !rotate) at.fail("missing key \"translate\" or \"rotate\" (give one or both)");
      if (translate) op.translate = vec2(*translate, at, "translate");
      if (rotate) op.rotate = number(*rotate, at, "rotate");
      break;
    }
    case EditOp::Kind::kColor: {
      const std::string mode = string_value(fields.required("mode"), at, "mode");
      if (mode == "blend") {
        op.mode = ColorMode::kBlend;
      } else if (mode == "transform") {
        op.mode = ColorMode::kTransform;
      } else {
        at.fail("mode", "expected \"blend\" or \"transform\", got \"" + printable(mode) + "\"");
      }
      at.op = "color " + mode;
      in_object();
      op.select = select(true);
      // Listed vertices need no point.
      if (op.select == EditSelect::kVertices) {
        vertex_list();
        if (const Json* a = fields.optional("at")) op.at = vec2(*a, at, "at");
      } else {
        op.at = vec2(fields.required("at"), at, "at");
      }
      op.color = color(fields.required("color"), at, "color");
      op.radius = default_color_radius(op.select);
      if (const Json* r = fields.optional("radius")) {
        op.radius = number(*r, at, "radius");
        if (op.radius < 0) at.fail("radius", "expected a number >= 0, got " + num(op.radius));
      }
      if (const Json* t = fields.optional("tolerance")) {
        if (op.select != EditSelect::kRegion) at.fail("tolerance", "applies to \"select\": \"region\" only");
        op.tolerance = number(*t, at, "tolerance");
        if (op.tolerance < 0) at.fail("tolerance", "expected a number >= 0, got " + num(op.tolerance));
      }
      if (op.mode == ColorMode::kBlend) {
        if (const Json* a = fields.optional("amount")) {
          op.amount = number(*a, at, "amount");
          if (!(op.amount >= 0 && op.amount <= 1)) {
            at.fail("amount", "expected a number from 0 to 1, got " + num(op.amount));
          }
        }
      }
      break;
    }
  }
  fields.finish();
  return op;
}

// Duplicate keys and depth, checked while parsing (nlohmann keeps the last duplicate silently).
struct DuplicateKeys {
  std::vector<std::set<std::string>> keys;
  int depth = 0;
  bool operator()(int, Json::parse_event_t event, Json& parsed) {
    using E = Json::parse_event_t;
    if (event == E::object_start || event == E::array_start) {
      if (++depth > kMaxDepth) {
        throw Error(ErrorCode::kBadFile, "the ops file nests deeper than " + std::to_string(kMaxDepth) + " levels");
      }
      keys.emplace_back();
    } else if (event == E::object_end || event == E::array_end) {
      --depth;
      keys.pop_back();
    } else if (event == E::key && !keys.back().insert(parsed.get<std::string>()).second) {
      throw Error(ErrorCode::kBadFile,
                  "duplicate key \"" + printable(parsed.get<std::string>()) + "\" in the ops file");
    }
    return true;
  }
};

// ---- applying --------------------------------------------------------------------------------

[[noreturn]] void refuse(const std::string& where, const std::string& message) {
  throw Error(ErrorCode::kInvalidArgument, where + ": " + message);
}

std::string vertex_name(const ControlMesh& mesh, int v) {
  return "vertex " + std::to_string(v) + " " + point(mesh.positions[v]);
}

std::string feature_name(const ControlMesh& mesh, int f) {
  return "feature " + std::to_string(f) + " (id " + std::to_string(mesh.features[f].id) + ")";
}

bool is_object_op(EditOp::Kind kind) {
  using K = EditOp::Kind;
  return kind == K::kMakeObject || kind == K::kMoveObject || kind == K::kHideObject ||
         kind == K::kShowObject || kind == K::kOrderObject;
}

// The object operations (edit/objects.h); returns the log line's text.
template <class Inside, class Reach>
std::string apply_object_op(VectorImage& image, const EditOp& op, const std::string& where,
                            Inside&& inside, Reach&& within_reach) {
  using K = EditOp::Kind;
  const int count = static_cast<int>(image.objects.size());
  auto object_name = [&](int o) {
    const std::string& name = image.objects[o].name;
    return "object " + std::to_string(o) + (name.empty() ? "" : " (\"" + printable(name) + "\")");
  };
  if (op.kind != K::kMakeObject && op.object >= count) {
    refuse(where, "object " + std::to_string(op.object) + " is out of range (the image has " +
                      std::to_string(count) + (count == 1 ? " object)" : " objects)"));
  }
  try {
    switch (op.kind) {
      case K::kMakeObject: {
        if (op.rect) {
          const auto [x, y, rw, rh] = *op.rect;
          const MakeObjectResult r = make_object_in_rect(image, op.level, {x, y, rw, rh}, op.object_name);
          return object_name(r.object) + " made of what [" + std::to_string(x) + ", " + std::to_string(y) +
                 ", " + std::to_string(rw) + ", " + std::to_string(rh) + "] frames: " +
                 std::to_string(r.object_vertices) + " vertices, " + std::to_string(r.features_moved) +
                 (r.features_moved == 1 ? " feature" : " features") + " inside; the background under it has " +
                 std::to_string(r.fill_vertices) + " vertices (" + std::to_string(r.removed) + " removed)";
        }
        inside("at", op.at);
        const ControlMesh& mesh = image.levels[op.level];
        const int f = closed_feature_around(mesh, op.at);
        if (f < 0) refuse(where, "no closed feature of level " + std::to_string(op.level) + " encloses " + point(op.at));
        const std::string feature = feature_name(mesh, f);
        // make_object drops the next level's pyramid link itself.
        const MakeObjectResult r = make_object(image, op.level, f, op.object_name);
        return object_name(r.object) + " made of the region inside " + feature + ": " +
               std::to_string(r.object_vertices) + " vertices, " + std::to_string(r.features_moved) +
               (r.features_moved == 1 ? " feature" : " features") + " inside; the background under it has " +
               std::to_string(r.fill_vertices) + " vertices (" + std::to_string(r.removed) + " removed)";
      }
      case K::kMoveObject: {
        within_reach(op.translate);
        ObjectTransform t;
        t.translate = op.translate;
        t.rotate_degrees = op.rotate;
        t.scale = op.scale;
        t.pivot = op.pivot;
        const Vec2 pivot = op.pivot.value_or(object_center(image.objects[op.object]));
        transform_object(image, op.object, t);
        return object_name(op.object) + " scaled by " + num(op.scale) + " and rotated by " + num(op.rotate) +
               " degrees about " + point(pivot) + ", moved by " + point(op.translate);
      }
      case K::kHideObject:
      case K::kShowObject:
        set_object_visible(image, op.object, op.kind == K::kShowObject);
        return object_name(op.object) + (op.kind == K::kShowObject ? " shown" : " hidden");
      case K::kOrderObject: {
        if (op.position >= count) {
          refuse(where, "\"to\" " + std::to_string(op.position) + " is out of range (the image has " +
                            std::to_string(count) + (count == 1 ? " object)" : " objects)"));
        }
        const std::string name = object_name(op.object);
        reorder_object(image, op.object, op.position);
        return name + " moved to position " + std::to_string(op.position) + " of " + std::to_string(count) +
               " (0 is the bottom)";
      }
      default:
        break;
    }
  } catch (const Error& e) {
    const std::string message = e.what();
    if (message.rfind(where, 0) == 0) throw;
    refuse(where, message);
  }
  return "";
}

}  // namespace

std::string EditOp::name() const {
  switch (kind) {
    case Kind::kDrag:
      return select == EditSelect::kVertex ? "drag vertex" : "drag feature";
    case Kind::kMoveFeature:
      return "move-feature";
    case Kind::kColor:
      return mode == ColorMode::kBlend ? "color blend" : "color transform";
    case Kind::kMoveVertices:
      return "move-vertices";
    case Kind::kAddFeature:
      return "add-feature";
    case Kind::kDeleteFeature:
      return "delete-feature";
    case Kind::kMakeObject:
      return "make-object";
    case Kind::kMoveObject:
      return "move-object";
    case Kind::kHideObject:
      return "hide-object";
    case Kind::kShowObject:
      return "show-object";
    case Kind::kOrderObject:
      return "order-object";
  }
  return "?";
}

std::vector<EditOp> parse_edit_ops(std::string_view text) {
  Json doc;
  try {
    DuplicateKeys check;
    doc = Json::parse(text.begin(), text.end(),
                      [&check](int depth, Json::parse_event_t event, Json& parsed) {
                        return check(depth, event, parsed);
                      });
  } catch (const Json::exception& e) {
    // parse_error, and out_of_range for a number beyond double's range (1e400)
    std::string what = e.what();
    const size_t end = what.find("] ");
    if (!what.empty() && what[0] == '[' && end != std::string::npos) what.erase(0, end + 2);
    throw Error(ErrorCode::kBadFile, "invalid JSON in the ops file: " + printable(what, 200));
  }
  if (!doc.is_array()) {
    throw Error(ErrorCode::kBadFile, std::string("the ops file must be a JSON array of operations, got ") +
                                         type_name(doc));
  }
  std::vector<EditOp> ops;
  for (size_t i = 0; i < doc.size(); ++i) {
    Place at{i, {}};
    ops.push_back(parse_op(doc[i], at));
  }
  return ops;
}

std::vector<std::string> apply_edit_ops(VectorImage& image, std::span<const EditOp> ops) {
  std::vector<std::string> log;
  const double w = image.width, h = image.height;
  for (size_t i = 0; i < ops.size(); ++i) {
    const EditOp& op = ops[i];
    const std::string where = "ops[" + std::to_string(i) + "] (" + op.name() + ")";
    const int num_levels = static_cast<int>(image.levels.size());
    if (op.level < 0 || op.level >= num_levels) {
      refuse(where, "level " + std::to_string(op.level) + " is out of range (the image has " +
                        std::to_string(num_levels) + (num_levels == 1 ? " level)" : " levels)"));
    }
    auto inside = [&](const char* key, Vec2 p) {
      if (!(p.x >= 0 && p.x <= w && p.y >= 0 && p.y <= h)) {
        refuse(where, std::string("\"") + key + "\" " + point(p) + " is outside the image [0, " +
                          num(w) + "] x [0, " + num(h) + "]");
      }
    };
    // A move farther than the image is wide or high takes nothing anywhere (the frame holds every
    // control point): it is a mistake, not an edit.
    auto within_reach = [&](Vec2 t) {
      if (!(std::abs(t.x) <= w && std::abs(t.y) <= h)) {
        refuse(where, "\"translate\" " + point(t) + " is larger than the image (" + num(w) + " x " +
                          num(h) + ")");
      }
    };
    if (is_object_op(op.kind)) {
      log.push_back(where + ": " + apply_object_op(image, op, where, inside, within_reach));
      continue;
    }
    // The mesh edited: the level's, or an object's (its own mesh, with no image frame around it).
    if (op.in_object && op.object >= static_cast<int>(image.objects.size())) {
      const int count = static_cast<int>(image.objects.size());
      refuse(where, "object " + std::to_string(op.object) + " is out of range (the image has " +
                        std::to_string(count) + (count == 1 ? " object)" : " objects)"));
    }
    ControlMesh mesh = op.in_object ? image.objects[op.object].mesh : image.levels[op.level];
    auto check = [&](const ControlMesh& m) {
      if (!op.in_object) return validate_level(m, image.width, image.height, op.level);
      Object o;
      o.level = image.objects[op.object].level;
      o.mesh = m;
      return validate_object(o, image.width, image.height, num_levels, op.object);
    };
    const MeshTopology topology = check(mesh);
    // Shape edits and deletions pick among the tear features and the crease chains.
    const std::vector<Feature> chains = editable_chains(mesh, topology);
    auto pick_feature = [&](Vec2 p) {
      const FeaturePick pick = nearest_feature(chains, mesh, topology, p);
      if (pick.feature < 0) {
        refuse(where, "nothing to select: level " + std::to_string(op.level) + " has no features");
      }
      return pick;
    };
    // "feature 3 (id 12)", or "crease 2" for the third crease chain.
    auto chain_name = [&](int f) {
      return f < static_cast<int>(mesh.features.size())
                 ? feature_name(mesh, f)
                 : "crease " + std::to_string(f - static_cast<int>(mesh.features.size()));
    };
    std::string done;
    try {
      switch (op.kind) {
        case EditOp::Kind::kDrag:
        case EditOp::Kind::kMoveFeature:
        case EditOp::Kind::kMoveVertices: {
          if (op.kind == EditOp::Kind::kDrag && !drag_grabs(op.select)) {
            refuse(where, "a drag grabs a \"vertex\" or a \"feature\"");
          }
          Handles handles;
          if (op.kind == EditOp::Kind::kMoveVertices) {
            within_reach(op.translate);
            handles = move_vertices(mesh, op.vertices, op.translate);
            done = std::to_string(op.vertices.size()) +
                   (op.vertices.size() == 1 ? " control point" : " control points") +
                   " moved by " + point(op.translate);
          } else if (op.kind == EditOp::Kind::kDrag) {
            inside("from", op.from);
            inside("to", op.to);
            const Vec2 d{op.to.x - op.from.x, op.to.y - op.from.y};
            if (op.select == EditSelect::kVertex) {
              const int v = nearest_vertex(mesh, op.from);
              const Vec2 p = mesh.positions[v];
              if (!op.in_object && (p.x == 0 || p.x == w) && (p.y == 0 || p.y == h)) {
                refuse(where, "nothing to drag: the nearest control vertex to " + point(op.from) +
                                  " is the image corner " + point(p) + ", which stays fixed");
              }
              handles = drag_vertex(mesh, v, d);
              done = vertex_name(mesh, v) + " moved by " + point(d);
            } else {
              const FeaturePick pick = pick_feature(op.from);
              handles = drag_feature(mesh, chains[pick.feature], op.from, d, op.sigma);
              done = chain_name(pick.feature) + " (" + num(pick.distance) +
                     " px away) dragged by " + point(d) + ", sigma " + num(op.sigma);
            }
          } else {
            inside("at", op.at);
            within_reach(op.translate);
            const FeaturePick pick = pick_feature(op.at);
            handles = move_feature(mesh, chains[pick.feature], op.translate, op.rotate);
            done = chain_name(pick.feature) + " (" + num(pick.distance) +
                   " px away) rotated by " + num(op.rotate) + " degrees and moved by " +
                   point(op.translate);
          }
          handles.region = op.region;
          ShapeEditor editor(mesh, op.in_object ? MeshTopology::kNoFrame : image.width,
                             op.in_object ? MeshTopology::kNoFrame : image.height);
          mesh.positions = editor.deform(handles);
          double moved = 0;
          for (int v = 0; v < mesh.num_vertices(); ++v) {
            moved = std::max(moved, std::hypot(mesh.positions[v].x - editor.rest()[v].x,
                                               mesh.positions[v].y - editor.rest()[v].y));
          }
          done += "; " + std::to_string(handles.vertices.size()) + " handle vertices, largest move " +
                  num(moved) + " px";
          if (editor.reached() < 1) {
            done += "; stopped at " + num(std::floor(editor.reached() * 1000) / 10) +
                    " % of the way, the last position before the control mesh would fold" +
                    (editor.framed() ? " (the image frame stops it)" : "");
          } else if (editor.scale_fraction() < 1) {
            done += " (scale adjustment applied at " + num(editor.scale_fraction()) +
                    " to avoid a flip)";
          }
          break;
        }
        case EditOp::Kind::kAddFeature: {
          for (const Vec2& p : op.points) inside("points", p);
          const FeatureEditResult r = add_feature(mesh, image.width, image.height, op.points, op.feature_kind);
          const int n = static_cast<int>(r.curve.points.size());
          const bool tear = op.feature_kind == FeatureKind::kTear;
          done = std::string(r.curve.closed ? "closed " : "") + (tear ? "tear " + feature_name(mesh, r.feature) : "crease") +
                 " added: " + std::to_string(n) + " control points (fit within " + num(r.curve.deviation, 2) +
                 " px of the " + std::to_string(op.points.size()) + " drawn), ";
          if (r.pieces > 1 || r.junctions > 0) {
            done += std::to_string(r.pieces) + (r.pieces == 1 ? " piece" : " pieces") + " (" +
                    (!tear ? "" : r.pieces == 1 ? "feature " + std::to_string(r.feature) + ", "
                                                : "features " + std::to_string(r.feature) + " to " +
                                                      std::to_string(r.feature + r.pieces - 1) + ", ") +
                    std::to_string(r.junctions) + (r.junctions == 1 ? " junction" : " junctions") +
                    " with existing features), ";
          }
          done += std::to_string(r.vertices_added) + " vertices added, " + std::to_string(r.flips) +
                  " edges flipped, " + std::to_string(r.colors_refit) + " color values refitted";
          break;
        }
        case EditOp::Kind::kDeleteFeature: {
          inside("at", op.at);
          const FeaturePick pick = pick_feature(op.at);
          const std::string name = chain_name(pick.feature);
          const bool crease = pick.feature >= static_cast<int>(mesh.features.size());
          const FeatureEditResult r = crease ? delete_crease(mesh, image.width, image.height, chains[pick.feature])
                                             : delete_feature(mesh, image.width, image.height, pick.feature);
          done = name + " (" + num(pick.distance) + " px away) deleted, " + std::to_string(r.colors_refit) +
                 " color values refitted";
          break;
        }
        case EditOp::Kind::kMakeObject:
        case EditOp::Kind::kMoveObject:
        case EditOp::Kind::kHideObject:
        case EditOp::Kind::kShowObject:
        case EditOp::Kind::kOrderObject:
          break;  // applied above (apply_object_op)
        case EditOp::Kind::kColor: {
          if (op.select != EditSelect::kVertices) inside("at", op.at);
          const ColorSelection s = select_colors(mesh, topology, op.select, op.at, op.radius,
                                                 op.tolerance, op.vertices);
          if (s.colors.empty()) refuse(where, "nothing to select at " + point(op.at));
          const Color seed = mesh.colors[s.seed_color];
          if (op.mode == ColorMode::kBlend) {
            blend_colors(mesh, s.colors, op.color, op.amount);
          } else {
            transform_colors(mesh, s.colors, seed, op.color);
          }
          done = std::to_string(s.colors.size()) + " color values from seed " +
                 vertex_name(mesh, s.seed_vertex) + " (color " + num(seed.r) + ", " + num(seed.g) +
                 ", " + num(seed.b) + ")";
          break;
        }
      }
      check(mesh);
    } catch (const Error& e) {
      const std::string message = e.what();
      if (message.rfind(where, 0) == 0) throw;
      refuse(where, message);
    }
    // Strokes on the level follow a shape edit (issue 29): each point keeps its place in its
    // control triangle. All of the level's points go through one call (one point-location grid).
    const bool topology_edit = op.kind == EditOp::Kind::kAddFeature || op.kind == EditOp::Kind::kDeleteFeature;
    // (An object's strokes follow a shape edit inside it the same way.)
    auto carry_strokes = [&](const ControlMesh& before, std::vector<Stroke>& strokes, int level) {
      if (op.kind == EditOp::Kind::kColor || topology_edit) return;
      int carried = 0;
      std::vector<Vec2> points;
      for (const Stroke& stroke : strokes) {
        if (stroke.level != level) continue;
        points.insert(points.end(), stroke.points.begin(), stroke.points.end());
        ++carried;
      }
      if (carried == 0) return;
      transport_points(before.positions, mesh.positions, mesh.triangles, points);
      size_t next = 0;
      for (Stroke& stroke : strokes) {
        if (stroke.level != level) continue;
        std::copy_n(points.begin() + long(next), stroke.points.size(), stroke.points.begin());
        next += stroke.points.size();
      }
      done += "; " + std::to_string(carried) + (carried == 1 ? " stroke" : " strokes") + " carried along";
    };
    if (op.in_object) {
      Object& object = image.objects[op.object];
      carry_strokes(object.mesh, object.strokes, object.level);
      object.mesh = std::move(mesh);
      log.push_back(where + ": object " + std::to_string(op.object) + ": " + done);
      continue;
    }
    if (topology_edit && op.level + 1 < num_levels) {
      // The next level's link to this one (its parents' numbering) no longer holds.
      image.levels[op.level + 1].parent_vertices.clear();
      image.levels[op.level + 1].collapses.clear();
    }
    carry_strokes(image.levels[op.level], image.strokes, op.level);
    image.levels[op.level] = std::move(mesh);
    log.push_back(where + ": " + done);
  }
  return log;
}

}  // namespace subvec
