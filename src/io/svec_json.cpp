// The `.svec.json` form (docs/format.md): reading through nlohmann::json, writing by hand.
//
// Reading parses into a DOM with a callback that tracks the JSON path, rejects duplicate keys and
// limits nesting, then walks the DOM with strict checks (exact key sets, exact types, integers
// that are integers, finite numbers), then validates the image (mesh/validate.h). Every message
// names the JSON path, e.g. "levels[0].triangles[12][1]: expected an integer, got a string".
//
// Writing emits a fixed layout: one key per line down to the level arrays, whose elements are
// packed several per line up to 100 columns. Numbers use the shortest text that reads back to the
// same value (doubles for positions, 32-bit floats for colors), so writing is deterministic and a
// read-write round trip is exact.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <unordered_set>

#include "io/json_p.h"
#include "io/svec_p.h"
#include "subvec/core/error.h"
#include "subvec/io/svec.h"
#include "subvec/mesh/validate.h"

namespace subvec {
namespace {

// nlohmann's std::map objects parse about twice as fast as ordered_json; the one place where
// key order matters (metadata, kept in file order) records it while parsing.
using Json = nlohmann::json;
using svec_detail::kJsonVersion;
using svec_detail::kJsonObjectsVersion;

// ---------------------------------------------------------------------------------------------
// Parsing: path tracking, duplicate keys and depth.

class ParseTracker {
 public:
  bool on_event(nlohmann::json::parse_event_t event, Json& parsed) {
    using E = nlohmann::json::parse_event_t;
    switch (event) {
      case E::object_start:
      case E::array_start:
        begin_element();
        if (stack_.size() >= size_t(svec_detail::kMaxJsonDepth)) {
          throw Error(ErrorCode::kBadFile,
                      svec_detail::one_line(path(true)) + ": JSON nested deeper than " +
                          std::to_string(svec_detail::kMaxJsonDepth) + " levels");
        }
        stack_.push_back({event == E::object_start, {}, -1, {}});
        break;
      case E::key: {
        Frame& top = stack_.back();
        top.key = parsed.get_ref<const std::string&>();
        if (!top.keys.insert(top.key).second) {
          throw Error(ErrorCode::kBadFile,
                      svec_detail::one_line(path(false) + ": duplicate key \"" + top.key + "\""));
        }
        if (stack_.size() == 2 && stack_[0].key == "metadata") metadata_order_.push_back(top.key);
        break;
      }
      case E::value:
        begin_element();
        break;
      case E::object_end:
      case E::array_end:
        stack_.pop_back();
        break;
    }
    return true;
  }

  // Where the parser is: "levels[0].vertices[3][1]"; "(top level)" for the root.
  std::string path(bool with_top_key) const {
    std::string out;
    for (size_t i = 0; i < stack_.size(); ++i) {
      const Frame& f = stack_[i];
      if (f.object) {
        if (f.key.empty() || (!with_top_key && i + 1 == stack_.size())) continue;
        if (!out.empty()) out += '.';
        out += f.key;
      } else if (f.index >= 0) {
        out += '[' + std::to_string(f.index) + ']';
      }
    }
    return out.empty() ? "(top level)" : out;
  }

  // Keys of the top-level "metadata" object in file order.
  const std::vector<std::string>& metadata_order() const { return metadata_order_; }

  // The path of the element being parsed when the parser failed (one past the last one seen).
  std::string failure_path() {
    if (!stack_.empty() && !stack_.back().object) ++stack_.back().index;
    return path(true);
  }

 private:
  struct Frame {
    bool object;
    std::string key;
    int64_t index;
    std::unordered_set<std::string> keys;
  };
  void begin_element() {
    if (!stack_.empty() && !stack_.back().object) ++stack_.back().index;
  }
  std::vector<Frame> stack_;
  std::vector<std::string> metadata_order_;
};

// nlohmann's message without its "[json.exception.xxx] " prefix.
std::string json_error_text(const char* what) {
  std::string s = what;
  if (!s.empty() && s[0] == '[') {
    const size_t end = s.find("] ");
    if (end != std::string::npos) s.erase(0, end + 2);
  }
  return s;
}

// ---------------------------------------------------------------------------------------------
// Walking the DOM.

// A JSON path such as levels[0].triangles[12][1], built lazily: each node names its parent and a
// member or an index, and the text is made only when a message needs it.
struct Path {
  const Path* parent = nullptr;
  const char* key = nullptr;  // member name; nullptr for an array index (or the root)
  size_t index = 0;

  Path operator[](size_t i) const { return {this, nullptr, i}; }
  Path member(const char* k) const { return {this, k, 0}; }
  bool is_root() const { return parent == nullptr; }

  std::string str() const {
    if (is_root()) return "(top level)";
    std::string prefix = parent->is_root() ? std::string() : parent->str();
    if (key) return prefix.empty() ? std::string(key) : prefix + "." + key;
    return prefix + "[" + std::to_string(index) + "]";
  }
};

[[noreturn]] void fail(const Path& path, const std::string& message,
                       ErrorCode code = ErrorCode::kBadFile) {
  throw Error(code, svec_detail::one_line(path.str() + ": " + message));
}

const char* type_name(const Json& j) { return detail::json_type_name(j, true); }

// Rejects keys outside `allowed`, naming the first unknown one.
void check_keys(const Json& object, const Path& path, std::initializer_list<const char*> allowed) {
  for (const auto& item : object.items()) {
    const std::string& key = item.key();
    const bool known =
        std::any_of(allowed.begin(), allowed.end(), [&](const char* a) { return key == a; });
    if (!known) {
      std::string list;
      for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
      fail(path, "unknown key \"" + key + "\" (expected one of: " + list + ")");
    }
  }
}

const Json& object_at(const Json& j, const Path& path) {
  if (!j.is_object()) fail(path, std::string("expected an object, got ") + type_name(j));
  return j;
}

// The member `key` of `object`, or nullptr when absent (optional members).
const Json* find(const Json& object, const char* key) {
  auto it = object.find(key);
  return it == object.end() ? nullptr : &*it;
}

const Json& require(const Json& object, const Path& path, const char* key) {
  const Json* j = find(object, key);
  if (!j) fail(path, std::string("missing key \"") + key + "\"");
  return *j;
}

// An array of at most Limits::kMaxElements elements.
const Json& array_at(const Json& j, const Path& path) {
  if (!j.is_array()) fail(path, std::string("expected an array, got ") + type_name(j));
  if (static_cast<int64_t>(j.size()) > Limits::kMaxElements) {
    fail(path,
         std::to_string(j.size()) + " elements is over the limit of " +
             std::to_string(Limits::kMaxElements),
         ErrorCode::kLimit);
  }
  return j;
}

double number_at(const Json& j, const Path& path) {
  if (j.is_number_integer()) return static_cast<double>(j.get<int64_t>());
  if (j.is_number_unsigned()) return static_cast<double>(j.get<uint64_t>());
  if (!j.is_number_float()) fail(path, std::string("expected a number, got ") + type_name(j));
  const double v = j.get<double>();
  if (!std::isfinite(v)) fail(path, "number is not finite");
  return v;
}

float float_at(const Json& j, const Path& path) {
  const double v = number_at(j, path);
  if (std::abs(v) > std::numeric_limits<float>::max()) {
    fail(path, "number " + j.dump() + " is out of range for a 32-bit float");
  }
  return static_cast<float>(v);
}

int32_t int_at(const Json& j, const Path& path) {
  if (j.is_number_integer() || j.is_number_unsigned()) {
    const bool fits = j.is_number_unsigned()
                          ? j.get<uint64_t>() <= uint64_t(std::numeric_limits<int32_t>::max())
                          : j.get<int64_t>() >= std::numeric_limits<int32_t>::min() &&
                                j.get<int64_t>() <= std::numeric_limits<int32_t>::max();
    if (!fits) fail(path, "integer " + j.dump() + " is out of the 32-bit range");
    return static_cast<int32_t>(j.get<int64_t>());
  }
  fail(path, std::string("expected an integer, got ") + type_name(j) +
                 (j.is_number_float() ? " (" + j.dump() + ")" : ""));
}

// A fixed-size array such as [x, y] or [a, b, c], read element by element with `read`.
template <size_t N, typename T, typename Read>
std::array<T, N> tuple_at(const Json& j, const Path& path, const char* shape, Read read) {
  if (!j.is_array() || j.size() != N) {
    fail(path, std::string("expected ") + shape + ", got " +
                   (j.is_array() ? "an array of " + std::to_string(j.size()) + " elements"
                                 : type_name(j)));
  }
  std::array<T, N> out{};
  for (size_t k = 0; k < N; ++k) out[k] = read(j[k], path[k]);
  return out;
}

Vec2 vec2_at(const Json& j, const Path& path) {
  const auto v = tuple_at<2, double>(j, path, "[x, y]", number_at);
  return {v[0], v[1]};
}

Color color_at(const Json& j, const Path& path) {
  const auto v = tuple_at<3, float>(j, path, "[r, g, b]", float_at);
  return {v[0], v[1], v[2]};
}

template <typename T, typename Read>
std::vector<T> list_at(const Json& j, const Path& path, Read read) {
  const Json& array = array_at(j, path);
  std::vector<T> out;
  out.reserve(array.size());
  for (size_t i = 0; i < array.size(); ++i) out.push_back(read(array[i], path[i]));
  return out;
}

Feature feature_at(const Json& j, const Path& path) {
  object_at(j, path);
  check_keys(j, path, {"id", "vertices", "saliency"});
  Feature f;
  f.id = int_at(require(j, path, "id"), path.member("id"));
  f.vertices = list_at<int32_t>(require(j, path, "vertices"), path.member("vertices"), int_at);
  if (const Json* s = find(j, "saliency")) f.saliency = number_at(*s, path.member("saliency"));
  return f;
}

ControlMesh level_at(const Json& j, const Path& path) {
  object_at(j, path);
  check_keys(j, path,
             {"vertices", "colors", "triangles", "triangle_colors", "creases", "features",
              "parent_vertices", "collapses"});
  ControlMesh m;
  m.positions = list_at<Vec2>(require(j, path, "vertices"), path.member("vertices"), vec2_at);
  m.colors = list_at<Color>(require(j, path, "colors"), path.member("colors"), color_at);
  auto tri_at = [](const Json& t, const Path& p) {
    return tuple_at<3, int32_t>(t, p, "[a, b, c] (three integers)", int_at);
  };
  m.triangles = list_at<Tri>(require(j, path, "triangles"), path.member("triangles"), tri_at);
  if (const Json* tc = find(j, "triangle_colors")) {
    const Path p = path.member("triangle_colors");
    m.triangle_colors = list_at<Tri>(*tc, p, tri_at);
    if (m.triangle_colors.size() != m.triangles.size()) {
      fail(p, std::to_string(m.triangle_colors.size()) + " entries but there are " +
                  std::to_string(m.triangles.size()) + " triangles (one entry per triangle)");
    }
  } else {
    // Without triangle_colors each corner uses the color with its vertex's index.
    if (m.colors.size() != m.positions.size()) {
      fail(path, "\"triangle_colors\" is absent, so color i belongs to vertex i, but there are " +
                     std::to_string(m.positions.size()) + " vertices and " +
                     std::to_string(m.colors.size()) + " colors");
    }
    m.triangle_colors = m.triangles;
  }
  if (const Json* c = find(j, "creases")) {
    m.creases = list_at<EdgeVerts>(*c, path.member("creases"), [](const Json& e, const Path& p) {
      return tuple_at<2, int32_t>(e, p, "[a, b] (two vertex indices)", int_at);
    });
  }
  if (const Json* f = find(j, "features")) {
    m.features = list_at<Feature>(*f, path.member("features"), feature_at);
  }
  // The pyramid record of a coarser level (docs/format.md, "Levels and the pyramid").
  if (const Json* pv = find(j, "parent_vertices")) {
    m.parent_vertices = list_at<int32_t>(*pv, path.member("parent_vertices"), int_at);
  }
  if (const Json* c = find(j, "collapses")) {
    m.collapses = list_at<EdgeVerts>(*c, path.member("collapses"), [](const Json& e, const Path& p) {
      return tuple_at<2, int32_t>(e, p, "[removed, kept] (two vertex indices)", int_at);
    });
  }
  return m;
}

Stroke stroke_at(const Json& j, const Path& path);

Object object_at_path(const Json& j, const Path& path) {
  object_at(j, path);
  check_keys(j, path, {"level", "name", "visible", "mesh", "strokes"});
  Object o;
  if (const Json* l = find(j, "level")) o.level = int_at(*l, path.member("level"));
  if (const Json* n = find(j, "name")) {
    if (!n->is_string()) fail(path.member("name"), std::string("expected a string, got ") + type_name(*n));
    o.name = n->get<std::string>();
  }
  if (const Json* v = find(j, "visible")) {
    if (!v->is_boolean()) fail(path.member("visible"), std::string("expected true or false, got ") + type_name(*v));
    o.visible = v->get<bool>();
  }
  o.mesh = level_at(require(j, path, "mesh"), path.member("mesh"));
  if (const Json* s = find(j, "strokes")) o.strokes = list_at<Stroke>(*s, path.member("strokes"), stroke_at);
  return o;
}

Stroke stroke_at(const Json& j, const Path& path) {
  object_at(j, path);
  check_keys(j, path, {"level", "points", "width", "color", "taper"});
  Stroke s;
  if (const Json* l = find(j, "level")) s.level = int_at(*l, path.member("level"));
  s.points = list_at<Vec2>(require(j, path, "points"), path.member("points"), vec2_at);
  s.width = float_at(require(j, path, "width"), path.member("width"));
  s.color = color_at(require(j, path, "color"), path.member("color"));
  if (const Json* t = find(j, "taper")) s.taper = float_at(*t, path.member("taper"));
  return s;
}

VectorImage image_from(const Json& root, const std::vector<std::string>& metadata_order) {
  const Path top;
  if (!root.is_object()) fail(top, std::string("expected a JSON object, got ") + type_name(root));
  const Json& format = require(root, top, "format");
  if (!format.is_string() || format.get_ref<const std::string&>() != "subvec") {
    fail(top.member("format"),
         "expected \"subvec\", got " + format.dump(-1, ' ', true) + " (this is not a subvec file)");
  }
  const int version = int_at(require(root, top, "version"), top.member("version"));
  if (version != kJsonVersion && version != kJsonObjectsVersion) {
    fail(top.member("version"), "unsupported .svec.json version " + std::to_string(version) +
                                    " (this build reads " + std::to_string(kJsonVersion) + " and " +
                                    std::to_string(kJsonObjectsVersion) + ")");
  }
  if (version == kJsonVersion) {
    check_keys(root, top, {"format", "version", "width", "height", "levels", "strokes", "metadata"});
  } else {
    check_keys(root, top,
               {"format", "version", "width", "height", "levels", "objects", "strokes", "metadata"});
  }

  VectorImage image;
  image.width = int_at(require(root, top, "width"), top.member("width"));
  image.height = int_at(require(root, top, "height"), top.member("height"));
  const Path levels_path = top.member("levels");
  const Json& levels = array_at(require(root, top, "levels"), levels_path);
  if (static_cast<int64_t>(levels.size()) > Limits::kMaxLevels) {
    fail(levels_path,
         std::to_string(levels.size()) + " levels is over the limit of " +
             std::to_string(Limits::kMaxLevels),
         ErrorCode::kLimit);
  }
  for (size_t l = 0; l < levels.size(); ++l)
    image.levels.push_back(level_at(levels[l], levels_path[l]));
  if (const Json* o = find(root, "objects")) {
    const Path objects_path = top.member("objects");
    const Json& objects = array_at(*o, objects_path);
    if (static_cast<int64_t>(objects.size()) > Limits::kMaxObjects) {
      fail(objects_path,
           std::to_string(objects.size()) + " objects is over the limit of " +
               std::to_string(Limits::kMaxObjects),
           ErrorCode::kLimit);
    }
    for (size_t k = 0; k < objects.size(); ++k) image.objects.push_back(object_at_path(objects[k], objects_path[k]));
  }
  if (const Json* s = find(root, "strokes")) {
    image.strokes = list_at<Stroke>(*s, top.member("strokes"), stroke_at);
  }
  if (const Json* m = find(root, "metadata")) {
    const Path metadata_path = top.member("metadata");
    object_at(*m, metadata_path);
    for (const std::string& key : metadata_order) {
      const Json& value = m->at(key);
      if (!value.is_string()) {
        fail(metadata_path.member(key.c_str()),
             std::string("expected a string, got ") + type_name(value));
      }
      image.metadata.emplace_back(key, value.get<std::string>());
    }
  }
  return image;
}

// ---------------------------------------------------------------------------------------------
// Writing.

std::string format_double(double v) {
  if (v == 0) return "0";  // also folds -0
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

// Shortest text that reads back (as a double, then rounded to float, as the reader does) to `v`.
std::string format_float(float v) {
  if (v == 0) return "0";
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, r.ptr);
  if (static_cast<float>(std::strtod(s.c_str(), nullptr)) == v) return s;
  return format_double(static_cast<double>(v));
}

class JsonWriter {
 public:
  static constexpr size_t kWidth = 100;

  std::string out;

  void line(int indent, const std::string& text) {
    out.append(size_t(indent) * 2, ' ');
    out += text;
    out += '\n';
  }

  // `"key": [item, item, ...]` with a trailing `comma`: on one line when it fits, otherwise the
  // items packed several per line, one indent deeper.
  void list(int indent, const std::string& key, const std::vector<std::string>& items, bool comma) {
    const std::string head = key.empty() ? "[" : "\"" + key + "\": [";
    const std::string tail = comma ? "]," : "]";
    size_t inline_width = size_t(indent) * 2 + head.size() + tail.size();
    for (const auto& item : items) inline_width += item.size() + 2;
    if (inline_width <= kWidth + 2) {
      std::string text = head;
      for (size_t i = 0; i < items.size(); ++i) text += (i ? ", " : "") + items[i];
      line(indent, text + tail);
      return;
    }
    line(indent, head);
    std::string current;
    const size_t room = kWidth - size_t(indent + 1) * 2;
    for (size_t i = 0; i < items.size(); ++i) {
      const std::string piece = items[i] + (i + 1 < items.size() ? "," : "");
      if (!current.empty() && current.size() + 1 + piece.size() > room) {
        line(indent + 1, current);
        current.clear();
      }
      current += (current.empty() ? "" : " ") + piece;
    }
    if (!current.empty()) line(indent + 1, current);
    line(indent, tail);
  }
};

std::string vec2_text(Vec2 p) { return "[" + format_double(p.x) + ", " + format_double(p.y) + "]"; }
std::string color_text(Color c) {
  return "[" + format_float(c.r) + ", " + format_float(c.g) + ", " + format_float(c.b) + "]";
}
template <size_t N>
std::string ints_text(const std::array<int32_t, N>& a) {
  std::string s = "[";
  for (size_t k = 0; k < N; ++k) s += (k ? ", " : "") + std::to_string(a[k]);
  return s + "]";
}

template <typename T, typename F>
std::vector<std::string> texts(const std::vector<T>& items, F f) {
  std::vector<std::string> out;
  out.reserve(items.size());
  for (const T& item : items) out.push_back(f(item));
  return out;
}

std::string string_text(const std::string& s) {
  try {
    return Json(s).dump(-1, ' ', false, Json::error_handler_t::strict);
  } catch (const nlohmann::json::exception&) {
    throw Error(ErrorCode::kInvalidArgument, "metadata string is not valid UTF-8");
  }
}

// One mesh as a JSON object, `base` levels deeper than a level of "levels".
void write_level(JsonWriter& w, const ControlMesh& m, bool last, int base = 0, const std::string& name = "") {
  const bool implicit_colors =
      m.colors.size() == m.positions.size() && m.triangle_colors == m.triangles;
  w.line(base + 2, name.empty() ? "{" : "\"" + name + "\": {");
  std::vector<const char*> keys = {"vertices", "colors", "triangles"};
  if (!implicit_colors) keys.push_back("triangle_colors");
  if (!m.creases.empty()) keys.push_back("creases");
  if (!m.features.empty()) keys.push_back("features");
  if (!m.parent_vertices.empty()) keys.push_back("parent_vertices");
  if (!m.collapses.empty()) keys.push_back("collapses");
  for (size_t k = 0; k < keys.size(); ++k) {
    const std::string key = keys[k];
    const bool comma = k + 1 < keys.size();
    if (key == "vertices") w.list(base + 3, key, texts(m.positions, vec2_text), comma);
    if (key == "colors") w.list(base + 3, key, texts(m.colors, color_text), comma);
    if (key == "triangles") w.list(base + 3, key, texts(m.triangles, ints_text<3>), comma);
    if (key == "triangle_colors") w.list(base + 3, key, texts(m.triangle_colors, ints_text<3>), comma);
    if (key == "creases") w.list(base + 3, key, texts(m.creases, ints_text<2>), comma);
    if (key == "parent_vertices")
      w.list(base + 3, key, texts(m.parent_vertices, [](int32_t v) { return std::to_string(v); }), comma);
    if (key == "collapses") w.list(base + 3, key, texts(m.collapses, ints_text<2>), comma);
    if (key == "features") {
      w.line(base + 3, "\"features\": [");
      for (size_t i = 0; i < m.features.size(); ++i) {
        const Feature& f = m.features[i];
        const auto vertices = texts(f.vertices, [](int32_t v) { return std::to_string(v); });
        const std::string end = i + 1 < m.features.size() ? "}," : "}";
        // Short features on one line; long ones with their vertex list wrapped.
        std::string text = "{\"id\": " + std::to_string(f.id) +
                           ", \"saliency\": " + format_double(f.saliency) + ", \"vertices\": [";
        for (size_t j = 0; j < vertices.size(); ++j) text += (j ? ", " : "") + vertices[j];
        text += "]" + end;
        if (8 + text.size() <= JsonWriter::kWidth) {
          w.line(base + 4, text);
        } else {
          w.line(base + 4, "{");
          w.line(base + 5, "\"id\": " + std::to_string(f.id) + ",");
          w.line(base + 5, "\"saliency\": " + format_double(f.saliency) + ",");
          w.list(base + 5, "vertices", vertices, false);
          w.line(base + 4, end);
        }
      }
      w.line(base + 3, comma ? "]," : "]");
    }
  }
  w.line(base + 2, last ? "}" : "},");
}

// A "strokes" member at `indent`, its entries one deeper.
void write_strokes(JsonWriter& w, const std::vector<Stroke>& strokes, int indent, bool last) {
  w.line(indent, "\"strokes\": [");
  for (size_t i = 0; i < strokes.size(); ++i) {
    const Stroke& s = strokes[i];
    w.line(indent + 1, "{");
    w.line(indent + 2, "\"level\": " + std::to_string(s.level) + ",");
    w.line(indent + 2, "\"width\": " + format_float(s.width) + ",");
    w.line(indent + 2, "\"color\": " + color_text(s.color) + ",");
    w.line(indent + 2, "\"taper\": " + format_float(s.taper) + ",");
    w.list(indent + 2, "points", texts(s.points, vec2_text), false);
    w.line(indent + 1, i + 1 < strokes.size() ? "}," : "}");
  }
  w.line(indent, last ? "]" : "],");
}

}  // namespace

VectorImage parse_svec_json(std::string_view text) {
  if (static_cast<int64_t>(text.size()) > svec_detail::kMaxFileBytes) {
    throw Error(ErrorCode::kLimit, "JSON text of " + std::to_string(text.size()) +
                                       " bytes is over the limit of " +
                                       std::to_string(svec_detail::kMaxFileBytes));
  }
  ParseTracker tracker;
  Json root;
  try {
    root = Json::parse(
        text.begin(), text.end(),
        [&tracker](int, nlohmann::json::parse_event_t event, Json& parsed) {
          return tracker.on_event(event, parsed);
        },
        /*allow_exceptions=*/true, /*ignore_comments=*/false);
  } catch (const nlohmann::json::parse_error& e) {
    throw Error(ErrorCode::kBadFile,
                svec_detail::one_line("invalid JSON near " + tracker.failure_path() + " (byte " +
                                      std::to_string(e.byte) + "): " + json_error_text(e.what())));
  } catch (const nlohmann::json::exception& e) {
    throw Error(ErrorCode::kBadFile,
                svec_detail::one_line("invalid JSON at " + tracker.failure_path() + ": " +
                                      json_error_text(e.what())));
  }
  VectorImage image = image_from(root, tracker.metadata_order());
  validate(image);
  return image;
}

std::string to_svec_json(const VectorImage& image) {
  JsonWriter w;
  w.line(0, "{");
  w.line(1, "\"format\": \"subvec\",");
  // Version 1 unless there are objects, so that files without them are as they always were.
  w.line(1, "\"version\": " +
                std::to_string(image.objects.empty() ? kJsonVersion : kJsonObjectsVersion) + ",");
  w.line(1, "\"width\": " + std::to_string(image.width) + ",");
  w.line(1, "\"height\": " + std::to_string(image.height) + ",");
  const bool more_after_objects = !image.strokes.empty() || !image.metadata.empty();
  const bool more_after_levels = !image.objects.empty() || more_after_objects;
  w.line(1, "\"levels\": [");
  for (size_t l = 0; l < image.levels.size(); ++l)
    write_level(w, image.levels[l], l + 1 == image.levels.size());
  w.line(1, more_after_levels ? "]," : "]");
  if (!image.objects.empty()) {
    w.line(1, "\"objects\": [");
    for (size_t k = 0; k < image.objects.size(); ++k) {
      const Object& o = image.objects[k];
      w.line(2, "{");
      w.line(3, "\"level\": " + std::to_string(o.level) + ",");
      w.line(3, "\"name\": " + string_text(o.name) + ",");
      w.line(3, std::string("\"visible\": ") + (o.visible ? "true" : "false") + ",");
      write_level(w, o.mesh, o.strokes.empty(), 1, "mesh");
      if (!o.strokes.empty()) write_strokes(w, o.strokes, 3, true);
      w.line(2, k + 1 < image.objects.size() ? "}," : "}");
    }
    w.line(1, more_after_objects ? "]," : "]");
  }
  if (!image.strokes.empty()) write_strokes(w, image.strokes, 1, image.metadata.empty());
  if (!image.metadata.empty()) {
    w.line(1, "\"metadata\": {");
    for (size_t i = 0; i < image.metadata.size(); ++i) {
      const auto& [key, value] = image.metadata[i];
      w.line(2, string_text(key) + ": " + string_text(value) +
                    (i + 1 < image.metadata.size() ? "," : ""));
    }
    w.line(1, "}");
  }
  w.line(0, "}");
  return std::move(w.out);
}

}  // namespace subvec
