// subvec._subvec: the pybind11 bindings behind the Python package `subvec` (docs/python.md).
//
// A front end like the CLI: it translates arguments into the library's parameter structs and
// results into NumPy arrays and dicts, and adds no algorithm of its own. Policies:
// - Errors: subvec::Error becomes an exception whose class follows its ErrorCode (kErrorClasses);
//   every class derives from subvec.Error and from the closest built-in (ValueError, OSError).
// - The GIL is released around every call into the library that can take long (vectorize, render,
//   load, save, edits, stylize, subdivision), so Python threads (and Dask's threaded workers) run
//   images in parallel. Arguments are converted before and results after, with the GIL held.
//   One VectorImage must not be mutated from two threads at once.
// - Arrays are copied in and out: a VectorImage owns its data, and an array a caller keeps never
//   aliases it.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "subvec/core/error.h"
#include "subvec/core/metrics.h"
#include "subvec/edit/color.h"
#include "subvec/edit/ops.h"
#include "subvec/edit/selection.h"
#include "subvec/edit/shape.h"
#include "subvec/edit/stylize.h"
#include "subvec/io/image_io.h"
#include "subvec/io/svec.h"
#include "subvec/mesh/topology.h"
#include "subvec/mesh/validate.h"
#include "subvec/pyramid/pyramid.h"
#include "subvec/render/renderer.h"
#include "subvec/subdiv/subdivision.h"
#include "subvec/vectorize/vectorize.h"

#ifndef SUBVEC_VERSION
#define SUBVEC_VERSION "unknown"
#endif

namespace py = pybind11;
using namespace pybind11::literals;

namespace {

using subvec::Error;
using subvec::ErrorCode;
using subvec::VectorImage;

// ---- exceptions ------------------------------------------------------------------------------

// Indexed by ErrorCode; filled once at import.
std::array<PyObject*, 6> kErrorClasses{};
PyObject* kBaseError = nullptr;

PyObject* new_exception(py::module_& m, const char* name, py::tuple bases, const char* doc) {
  const std::string qualified = std::string("subvec.") + name;
  PyObject* cls = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
  if (!cls) throw py::error_already_set();
  m.attr(name) = py::handle(cls);  // the module keeps a reference; so does this file, for good
  return cls;
}

void register_exceptions(py::module_& m) {
  const py::handle value_error(PyExc_ValueError), os_error(PyExc_OSError);
  kBaseError = new_exception(m, "Error", py::make_tuple(py::handle(PyExc_Exception)),
                             "Base class of every error raised by subvec.");
  const py::handle base(kBaseError);
  kErrorClasses[size_t(ErrorCode::kInvalidArgument)] =
      new_exception(m, "InvalidArgumentError", py::make_tuple(base, value_error),
                    "An argument or option out of its range (shape, dtype, level, window, ...).");
  kErrorClasses[size_t(ErrorCode::kInvalidMesh)] =
      new_exception(m, "InvalidMeshError", py::make_tuple(base, value_error),
                    "A vector image that breaks an invariant of the model (docs/format.md).");
  kErrorClasses[size_t(ErrorCode::kBadFile)] =
      new_exception(m, "BadFileError", py::make_tuple(base, value_error),
                    "A file that cannot be parsed: truncated, wrong magic, a bad field.");
  kErrorClasses[size_t(ErrorCode::kIo)] =
      new_exception(m, "FileError", py::make_tuple(base, os_error),
                    "The operating system refused a read or a write (missing file, permissions).");
  kErrorClasses[size_t(ErrorCode::kLimit)] =
      new_exception(m, "LimitError", py::make_tuple(base, value_error),
                    "An input over a size limit (pixels, vertices, bytes).");
  kErrorClasses[size_t(ErrorCode::kCancelled)] =
      new_exception(m, "CancelledError", py::make_tuple(base),
                    "A long job stopped because it was asked to (its cancel flag was set).");
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      const auto code = static_cast<size_t>(e.code());
      PyErr_SetString(code < kErrorClasses.size() ? kErrorClasses[code] : kBaseError, e.what());
    }
  });
}

[[noreturn]] void invalid(const std::string& message) {
  throw Error(ErrorCode::kInvalidArgument, message);
}

// ---- arrays ----------------------------------------------------------------------------------

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

// H x W x 3 uint8 (as is) or float32 / float64 in [0, 1] (round(255 v)) -> RGB Image8.
subvec::Image8 image_from_array(const py::object& object) {
  const py::array a = py::array::ensure(object);
  if (!a) {
    PyErr_Clear();
    invalid("expected an H x W x 3 array, got " + py::repr(object).cast<std::string>());
  }
  if (a.ndim() != 3 || a.shape(2) != 3) {
    invalid("expected an H x W x 3 RGB array, got shape " + shape_text(a));
  }
  const py::ssize_t h = a.shape(0), w = a.shape(1);
  if (h < 1 || w < 1) invalid("the image is empty: shape " + shape_text(a));
  if (h > subvec::Limits::kMaxDimension || w > subvec::Limits::kMaxDimension) {
    throw Error(ErrorCode::kLimit, "image of " + std::to_string(w) + " x " + std::to_string(h) +
                                       " pixels is over the limit of " +
                                       std::to_string(subvec::Limits::kMaxDimension) + " a side");
  }
  subvec::Image8 out(static_cast<int>(w), static_cast<int>(h), 3);
  const py::dtype dt = a.dtype();
  if (dt.is(py::dtype::of<uint8_t>())) {
    const auto c = py::array_t<uint8_t, py::array::c_style | py::array::forcecast>::ensure(a);
    std::memcpy(out.pixels.data(), c.data(), out.pixels.size());
    return out;
  }
  if (dt.is(py::dtype::of<float>()) || dt.is(py::dtype::of<double>())) {
    const auto c = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
    const double* v = c.data();
    for (size_t i = 0; i < out.pixels.size(); ++i) {
      if (!(v[i] >= 0.0 && v[i] <= 1.0)) {
        invalid("float images hold values in [0, 1]; element " + std::to_string(i) + " is " +
                std::to_string(v[i]));
      }
      out.pixels[i] = static_cast<uint8_t>(std::lround(v[i] * 255.0));
    }
    return out;
  }
  invalid("expected a uint8 or float32 array, got dtype " + py::str(static_cast<const py::handle&>(dt)).cast<std::string>());
}

py::array_t<uint8_t> array_from_image(const subvec::Image8& image) {
  py::array_t<uint8_t> out({py::ssize_t(image.height), py::ssize_t(image.width),
                            py::ssize_t(image.channels)});
  std::memcpy(out.mutable_data(), image.pixels.data(), image.pixels.size());
  return out;
}

template <typename T, typename Source>
py::array_t<T> matrix(const Source* data, size_t rows, size_t cols) {
  py::array_t<T> out({py::ssize_t(rows), py::ssize_t(cols)});
  T* dst = out.mutable_data();
  for (size_t i = 0; i < rows * cols; ++i) dst[i] = static_cast<T>(data[i]);
  return out;
}

py::array_t<int32_t> index_vector(const std::vector<int32_t>& v) {
  py::array_t<int32_t> out(py::ssize_t(v.size()));
  if (!v.empty()) std::memcpy(out.mutable_data(), v.data(), v.size() * sizeof(int32_t));
  return out;
}

// An Eigen row-major sparse matrix as the pieces of CSR: (data, indices, indptr, shape).
py::tuple csr(const subvec::SparseMatrix& s) {
  subvec::SparseMatrix m = s;
  m.makeCompressed();
  const auto nnz = size_t(m.nonZeros());
  py::array_t<double> data{py::ssize_t(nnz)};
  py::array_t<int32_t> indices{py::ssize_t(nnz)};
  py::array_t<int32_t> indptr(py::ssize_t(m.rows() + 1));
  if (nnz) {
    std::memcpy(data.mutable_data(), m.valuePtr(), nnz * sizeof(double));
    std::memcpy(indices.mutable_data(), m.innerIndexPtr(), nnz * sizeof(int32_t));
  }
  std::memcpy(indptr.mutable_data(), m.outerIndexPtr(), size_t(m.rows() + 1) * sizeof(int32_t));
  return py::make_tuple(data, indices, indptr, py::make_tuple(m.rows(), m.cols()));
}

// ---- argument checks -------------------------------------------------------------------------

int check_level(const VectorImage& image, int level) {
  const int n = static_cast<int>(image.levels.size());
  if (level < 0 || level >= n) {
    invalid("level " + std::to_string(level) + " is out of range: the image has " +
            std::to_string(n) + (n == 1 ? " level" : " levels") + " (0 to " +
            std::to_string(n - 1) + ")");
  }
  return level;
}

subvec::Vec2 point(const std::array<double, 2>& p, const char* what) {
  if (!std::isfinite(p[0]) || !std::isfinite(p[1])) invalid(std::string(what) + " is not finite");
  return {p[0], p[1]};
}

subvec::Color color3(const std::array<double, 3>& c, const char* what) {
  for (double v : c) {
    if (!std::isfinite(v)) invalid(std::string(what) + " is not finite");
  }
  return {float(c[0]), float(c[1]), float(c[2])};
}

// ---- VectorImage methods ---------------------------------------------------------------------

// Fills RenderOptions as `subvec render` does; the library resolves the output size and window
// (subvec::render_size), so render() and the CLI's PNG agree byte for byte.
subvec::Image8 render_image(const VectorImage& image, std::optional<int> width,
                            std::optional<double> scale, std::optional<std::array<double, 4>> win,
                            int level, const std::string& overlay, bool antialias, int threads,
                            int depth) {
  check_level(image, level);
  if (width && scale) invalid("give width or scale, not both");
  subvec::RenderOptions options;
  if (win) options.window = subvec::Window{(*win)[0], (*win)[1], (*win)[2], (*win)[3]};
  if (width) options.width = *width;
  if (scale) options.scale = *scale;  // the output limit: RenderOptions::max_pixels, as the CLI's
  options.level = level;
  if (overlay == "none") {
    options.overlay = subvec::Overlay::kNone;
  } else if (overlay == "mesh") {
    options.overlay = subvec::Overlay::kMesh;
  } else if (overlay == "features") {
    options.overlay = subvec::Overlay::kFeatures;
  } else {
    invalid("overlay must be 'none', 'mesh' or 'features', got '" + overlay + "'");
  }
  options.antialias = antialias;
  options.threads = threads;
  options.depth = depth;
  py::gil_scoped_release release;
  return subvec::render(image, options);
}

// The objects (mesh/vector_image.h), bottom to top.
py::list object_list(const VectorImage& image) {
  py::list objects;
  for (const subvec::Object& o : image.objects) {
    objects.append(py::dict("level"_a = o.level, "name"_a = o.name, "visible"_a = o.visible,
                            "vertices"_a = o.mesh.num_vertices(), "triangles"_a = o.mesh.num_triangles(),
                            "features"_a = o.mesh.features.size(), "strokes"_a = o.strokes.size()));
  }
  return objects;
}

py::dict info(const VectorImage& image) {
  py::list levels;
  for (const subvec::ControlMesh& mesh : image.levels) {
    const subvec::MeshTopology topo = subvec::MeshTopology::build(mesh, image.width, image.height);
    int tears = 0, creases = 0, border = 0, corners = 0;
    for (subvec::EdgeTag t : topo.edge_tags) {
      tears += t == subvec::EdgeTag::kTear;
      creases += t == subvec::EdgeTag::kCrease;
      border += t == subvec::EdgeTag::kBorder;
    }
    for (subvec::VertexTag t : topo.vertex_tags) corners += t == subvec::VertexTag::kCorner;
    levels.append(py::dict("vertices"_a = mesh.num_vertices(), "triangles"_a = mesh.num_triangles(),
                           "features"_a = mesh.features.size(), "tear_edges"_a = tears,
                           "colors"_a = mesh.num_colors(), "creases"_a = creases,
                           "border_edges"_a = border, "edges"_a = topo.num_edges(),
                           "corners"_a = corners));
  }
  py::dict metadata;
  for (const auto& [key, value] : image.metadata) metadata[py::str(key)] = value;
  return py::dict("width"_a = image.width, "height"_a = image.height, "levels"_a = levels,
                  "objects"_a = object_list(image), "strokes"_a = image.strokes.size(),
                  "metadata"_a = metadata);
}

py::dict mesh_dict_of(const subvec::ControlMesh& m);

py::dict mesh_dict(const VectorImage& image, int level) {
  return mesh_dict_of(image.levels[size_t(check_level(image, level))]);
}

py::dict object_mesh_dict(const VectorImage& image, int object) {
  if (object < 0 || object >= static_cast<int>(image.objects.size())) {
    throw py::index_error("object " + std::to_string(object) + " is out of range (" +
                          std::to_string(image.objects.size()) + " objects)");
  }
  return mesh_dict_of(image.objects[size_t(object)].mesh);
}

py::dict mesh_dict_of(const subvec::ControlMesh& m) {
  py::list features;
  for (const subvec::Feature& f : m.features) {
    features.append(py::dict("id"_a = f.id, "vertices"_a = index_vector(f.vertices),
                             "saliency"_a = f.saliency, "closed"_a = f.closed()));
  }
  return py::dict(
      "positions"_a = matrix<double>(&m.positions.data()->x, m.positions.size(), 2),
      "colors"_a = matrix<float>(&m.colors.data()->r, m.colors.size(), 3),
      "triangles"_a = matrix<int32_t>(m.triangles.data()->data(), m.triangles.size(), 3),
      "triangle_colors"_a =
          matrix<int32_t>(m.triangle_colors.data()->data(), m.triangle_colors.size(), 3),
      "creases"_a = matrix<int32_t>(m.creases.data()->data(), m.creases.size(), 2),
      "features"_a = features);
}

// Replaces one attribute channel of a level, keeping the old values when the result fails
// validation (a flipped triangle, a position outside the image).
template <typename T, typename Value>
void set_channel(VectorImage& image, int level, const py::object& object,
                 std::vector<Value>& (*field)(subvec::ControlMesh&), size_t cols, const char* name) {
  const py::array values = py::array::ensure(object);
  if (!values) {
    PyErr_Clear();
    invalid(std::string(name) + " must be an array");
  }
  subvec::ControlMesh& m = image.levels[size_t(check_level(image, level))];
  std::vector<Value>& dst = field(m);
  if (values.ndim() != 2 || size_t(values.shape(0)) != dst.size() || size_t(values.shape(1)) != cols) {
    invalid(std::string(name) + " must have shape (" + std::to_string(dst.size()) + ", " +
            std::to_string(cols) + "), got " + shape_text(values));
  }
  const auto c = py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(values);
  if (!c) throw py::error_already_set();
  std::vector<Value> old = dst;
  std::memcpy(static_cast<void*>(dst.data()), c.data(), dst.size() * sizeof(Value));
  try {
    py::gil_scoped_release release;
    subvec::validate_level(m, image.width, image.height, level);
  } catch (...) {
    dst = std::move(old);
    throw;
  }
}

std::vector<subvec::Vec2>& positions_of(subvec::ControlMesh& m) { return m.positions; }
std::vector<subvec::Color>& colors_of(subvec::ControlMesh& m) { return m.colors; }

// One edit operation through the library's ops (edit/ops.h): the same checks and messages as
// `subvec edit`.
std::string apply_op(VectorImage& image, const subvec::EditOp& op) {
  check_level(image, op.level);
  py::gil_scoped_release release;
  const std::vector<subvec::EditOp> ops{op};
  const std::vector<std::string> log = subvec::apply_edit_ops(image, ops);
  return log.empty() ? std::string() : log.front();
}

// An object index (or a position in the drawing order) in range, as an IndexError otherwise.
int object_index(const VectorImage& image, int object) {
  if (object < 0 || object >= static_cast<int>(image.objects.size())) {
    throw py::index_error("object " + std::to_string(object) + " is out of range (" +
                          std::to_string(image.objects.size()) + " objects)");
  }
  return object;
}

// An edit of object `object`'s own mesh instead of the level's (edit/ops.h, EditOp::in_object).
void in_object(const VectorImage& image, subvec::EditOp& op, std::optional<int> object) {
  if (!object) return;
  op.in_object = true;
  op.object = object_index(image, *object);
}

// The mesh an operation edits: its object's, or its level's.
const subvec::ControlMesh& mesh_of(const VectorImage& image, const subvec::EditOp& op) {
  return op.in_object ? image.objects[size_t(op.object)].mesh : image.levels[size_t(op.level)];
}

subvec::EditSelect parse_select(const std::string& s) {
  if (const std::optional<subvec::EditSelect> e = subvec::edit_select_from_name(s)) return *e;
  invalid("select must be 'vertex', 'feature', 'region', 'vertices' or 'all', got '" + s + "'");
}

// A color selection's reach: radius None is 0 for a vertex or feature and no cap for a region;
// the tolerance is the region's.
void color_reach(subvec::EditSelect select, const std::optional<double>& radius,
                 const std::optional<double>& tolerance, double& r, double& t) {
  const bool region = select == subvec::EditSelect::kRegion;
  r = radius ? *radius : subvec::default_color_radius(select);
  if (!(r >= 0)) invalid("radius must be >= 0");
  if (tolerance && !region) invalid("tolerance applies to select='region' only");
  t = tolerance ? *tolerance : subvec::kDefaultRegionTolerance;
  if (!(std::isfinite(t) && t >= 0)) invalid("tolerance must be >= 0");
}

std::vector<int32_t> index_list(const py::object& a, int limit, const char* what) {
  const auto c = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!c) PyErr_Clear();
  if (!c || c.ndim() != 1) invalid(std::string(what) + " must be a 1-D array of indices");
  std::vector<int32_t> out;
  out.reserve(size_t(c.size()));
  for (py::ssize_t i = 0; i < c.size(); ++i) {
    const int64_t v = c.data()[i];
    if (v < 0 || v >= limit) {
      invalid(std::string(what) + "[" + std::to_string(i) + "] = " + std::to_string(v) +
              " is out of range (0 to " + std::to_string(limit - 1) + ")");
    }
    out.push_back(static_cast<int32_t>(v));
  }
  return out;
}

// ---- the module, one topic at a time --------------------------------------------------------

using PyVectorImage = py::class_<VectorImage>;

// Properties, copies, rendering, serialization and the raw arrays of one level.
void def_vector_image(PyVectorImage& vi) {
  vi.def_property_readonly("width", [](const VectorImage& v) { return v.width; })
      .def_property_readonly("height", [](const VectorImage& v) { return v.height; })
      .def_property_readonly("num_levels", [](const VectorImage& v) { return v.levels.size(); })
      .def_property_readonly("num_strokes", [](const VectorImage& v) { return v.strokes.size(); })
      .def("__repr__",
           [](const VectorImage& v) {
             const int verts = v.levels.empty() ? 0 : v.levels.front().num_vertices();
             return "<subvec.VectorImage " + std::to_string(v.width) + "x" +
                    std::to_string(v.height) + ", " + std::to_string(v.levels.size()) +
                    (v.levels.size() == 1 ? " level" : " levels") + ", " +
                    std::to_string(verts) + " vertices>";
           })
      .def("copy", [](const VectorImage& v) { return VectorImage(v); })
      .def("__copy__", [](const VectorImage& v) { return VectorImage(v); })
      .def("__deepcopy__", [](const VectorImage& v, py::dict) { return VectorImage(v); }, "memo"_a)
      .def(
          "render",
          [](const VectorImage& v, std::optional<int> width, std::optional<double> scale,
             std::optional<std::array<double, 4>> window, int level, const std::string& overlay,
             bool antialias, int threads, int depth) {
            return array_from_image(
                render_image(v, width, scale, window, level, overlay, antialias, threads, depth));
          },
          py::kw_only(), "width"_a = py::none(), "scale"_a = py::none(), "window"_a = py::none(),
          "level"_a = 0, "overlay"_a = "none", "antialias"_a = true, "threads"_a = 0,
          "depth"_a = -1)
      .def(
          "save",
          [](const VectorImage& v, const std::filesystem::path& path, bool lossless, int compact_version) {
            subvec::SvecWriteOptions options;
            options.lossless = lossless;
            options.compact_version = compact_version;
            py::gil_scoped_release release;
            subvec::write_svec(path, v, options);
          },
          "path"_a, py::kw_only(), "lossless"_a = false, "compact_version"_a = 3)
      .def(
          "to_bytes",
          [](const VectorImage& v, const std::string& format, bool lossless, int compact_version) {
            std::string bytes;
            {
              py::gil_scoped_release release;
              if (format == "svec") {
                subvec::SvecWriteOptions options;
                options.lossless = lossless;
                options.compact_version = compact_version;
                const std::vector<uint8_t> b = subvec::to_svec_binary(v, options);
                bytes.assign(b.begin(), b.end());
              } else if (format == "json") {
                bytes = subvec::to_svec_json(v);
              } else {
                invalid("format must be 'svec' or 'json', got '" + format + "'");
              }
            }
            return py::bytes(bytes);
          },
          py::kw_only(), "format"_a = "svec", "lossless"_a = false, "compact_version"_a = 3)
      .def("info", &info)
      .def("mesh", &mesh_dict, py::kw_only(), "level"_a = 0)
      .def(
          "set_positions",
          [](VectorImage& v, const py::object& a, int level) {
            set_channel<double>(v, level, a, &positions_of, 2, "positions");
          },
          "positions"_a, py::kw_only(), "level"_a = 0)
      .def(
          "set_colors",
          [](VectorImage& v, const py::object& a, int level) {
            set_channel<float>(v, level, a, &colors_of, 3, "colors");
          },
          "colors"_a, py::kw_only(), "level"_a = 0);
}

// Edits (edit/ops.h): image coordinates, in pixels.
void def_edits(PyVectorImage& vi) {
  vi.def(
          "edit",
          [](VectorImage& v, const py::object& ops) {
            const std::string text = py::isinstance<py::str>(ops)
                                         ? ops.cast<std::string>()
                                         : py::module_::import("json").attr("dumps")(ops).cast<std::string>();
            py::gil_scoped_release release;
            const std::vector<subvec::EditOp> parsed = subvec::parse_edit_ops(text);
            return subvec::apply_edit_ops(v, parsed);
          },
          "ops"_a)
      .def(
          "drag",
          [](VectorImage& v, std::array<double, 2> from, std::array<double, 2> to,
             const std::string& select, double sigma, double region, int level, std::optional<int> object) {
            subvec::EditOp op;
            op.kind = subvec::EditOp::Kind::kDrag;
            op.select = parse_select(select);
            op.from = point(from, "from");
            op.to = point(to, "to");
            op.sigma = sigma;
            op.region = region;
            op.level = level;
            if (!(std::isfinite(sigma) && sigma > 0)) invalid("sigma must be a positive number");
            if (!(std::isfinite(region) && region >= 0)) invalid("region must be >= 0");
            in_object(v, op, object);
            return apply_op(v, op);
          },
          "from_"_a, "to"_a, py::kw_only(), "select"_a = "vertex", "sigma"_a = 20.0,
          "region"_a = 0.0, "level"_a = 0, "object"_a = py::none())
      .def(
          "move_feature",
          [](VectorImage& v, std::array<double, 2> at, std::array<double, 2> translate,
             double rotate, double region, int level, std::optional<int> object) {
            subvec::EditOp op;
            op.kind = subvec::EditOp::Kind::kMoveFeature;
            op.at = point(at, "at");
            op.translate = point(translate, "translate");
            if (!std::isfinite(rotate)) invalid("rotate is not finite");
            if (!(std::isfinite(region) && region >= 0)) invalid("region must be >= 0");
            op.rotate = rotate;
            op.region = region;
            op.level = level;
            in_object(v, op, object);
            return apply_op(v, op);
          },
          "at"_a, py::kw_only(), "translate"_a = std::array<double, 2>{0, 0}, "rotate"_a = 0.0,
          "region"_a = 0.0, "level"_a = 0, "object"_a = py::none())
      .def(
          "move_vertices",
          [](VectorImage& v, const py::object& vertices, std::array<double, 2> translate,
             double region, int level, std::optional<int> object) {
            subvec::EditOp op;
            op.kind = subvec::EditOp::Kind::kMoveVertices;
            op.level = check_level(v, level);
            in_object(v, op, object);
            op.vertices = index_list(vertices, mesh_of(v, op).num_vertices(), "vertices");
            op.translate = point(translate, "translate");
            if (!(std::isfinite(region) && region >= 0)) invalid("region must be >= 0");
            op.region = region;
            return apply_op(v, op);
          },
          "vertices"_a, "translate"_a, py::kw_only(), "region"_a = 0.0, "level"_a = 0, "object"_a = py::none())
      .def(
          "add_feature",
          [](VectorImage& v, const py::object& points, const std::string& kind, int level) {
            subvec::EditOp op;
            op.kind = subvec::EditOp::Kind::kAddFeature;
            for (const py::handle p : points) {
              std::array<double, 2> xy;
              try {
                xy = p.cast<std::array<double, 2>>();
              } catch (const py::cast_error&) {
                invalid("points must be a sequence of [x, y] pairs");
              }
              op.points.push_back(point(xy, "points"));
            }
            if (kind == "tear") {
              op.feature_kind = subvec::FeatureKind::kTear;
            } else if (kind == "crease") {
              op.feature_kind = subvec::FeatureKind::kCrease;
            } else {
              invalid("kind must be 'tear' or 'crease', got '" + kind + "'");
            }
            op.level = level;
            return apply_op(v, op);
          },
          "points"_a, py::kw_only(), "kind"_a = "tear", "level"_a = 0)
      .def(
          "make_object",
          [](VectorImage& v, std::optional<std::array<double, 2>> at, std::optional<std::array<int, 4>> rect,
             const std::string& name, int level) {
            subvec::EditOp op;
            op.kind = subvec::EditOp::Kind::kMakeObject;
            if (at.has_value() == rect.has_value()) invalid("give at or rect (one of them)");
            if (at) op.at = point(*at, "at");
            if (rect) {
              for (const int x : *rect) {
                if (x < 0) invalid("rect must be [x, y, width, height] with values >= 0");
              }
              op.rect = *rect;
            }
            op.object_name = name;
            op.level = level;
            return apply_op(v, op);
          },
          "at"_a = py::none(), py::kw_only(), "rect"_a = py::none(), "name"_a = "", "level"_a = 0)
      .def(
          "move_object",
          [](VectorImage& v, int object, std::array<double, 2> translate, double rotate, double scale,
             std::optional<std::array<double, 2>> pivot) {
            subvec::EditOp op;
            op.kind = subvec::EditOp::Kind::kMoveObject;
            op.object = object_index(v, object);
            op.translate = point(translate, "translate");
            if (!std::isfinite(rotate)) invalid("rotate is not finite");
            if (!(std::isfinite(scale) && scale > 0)) invalid("scale must be a positive number");
            op.rotate = rotate;
            op.scale = scale;
            if (pivot) op.pivot = point(*pivot, "pivot");
            return apply_op(v, op);
          },
          "object"_a, py::kw_only(), "translate"_a = std::array<double, 2>{0, 0}, "rotate"_a = 0.0,
          "scale"_a = 1.0, "pivot"_a = py::none())
      .def(
          "set_object_visible",
          [](VectorImage& v, int object, bool visible) {
            subvec::EditOp op;
            op.kind = visible ? subvec::EditOp::Kind::kShowObject : subvec::EditOp::Kind::kHideObject;
            op.object = object_index(v, object);
            return apply_op(v, op);
          },
          "object"_a, "visible"_a)
      .def(
          "order_object",
          [](VectorImage& v, int object, int to) {
            subvec::EditOp op;
            op.kind = subvec::EditOp::Kind::kOrderObject;
            op.object = object_index(v, object);
            op.position = object_index(v, to);
            return apply_op(v, op);
          },
          "object"_a, "to"_a)
      .def_property_readonly("objects", &object_list)
      .def("object_mesh", &object_mesh_dict, "object"_a)
      .def(
          "delete_feature",
          [](VectorImage& v, std::array<double, 2> at, int level) {
            subvec::EditOp op;
            op.kind = subvec::EditOp::Kind::kDeleteFeature;
            op.at = point(at, "at");
            op.level = level;
            return apply_op(v, op);
          },
          "at"_a, py::kw_only(), "level"_a = 0)
      .def(
          "recolor",
          [](VectorImage& v, std::optional<std::array<double, 2>> at, std::array<double, 3> color,
             const std::string& mode, const std::string& select, std::optional<double> radius,
             std::optional<double> tolerance, const py::object& vertices, double amount, int level, std::optional<int> object) {
            subvec::EditOp op;
            op.kind = subvec::EditOp::Kind::kColor;
            op.select = parse_select(select);
            // As in an ops file: a click point, except for select='vertices' (the points are given).
            if (at) {
              op.at = point(*at, "at");
            } else if (op.select != subvec::EditSelect::kVertices) {
              invalid("at is needed unless select='vertices'");
            }
            op.color = color3(color, "color");
            if (mode == "blend") {
              op.mode = subvec::ColorMode::kBlend;
            } else if (mode == "transform") {
              op.mode = subvec::ColorMode::kTransform;
            } else {
              invalid("mode must be 'blend' or 'transform', got '" + mode + "'");
            }
            color_reach(op.select, radius, tolerance, op.radius, op.tolerance);
            if ((op.select == subvec::EditSelect::kVertices) != !vertices.is_none()) {
              invalid("vertices go with select='vertices', and it needs them");
            }
            op.level = check_level(v, level);
            in_object(v, op, object);
            if (!vertices.is_none()) op.vertices = index_list(vertices, mesh_of(v, op).num_vertices(), "vertices");
            if (!(amount >= 0 && amount <= 1)) invalid("amount must be in [0, 1]");
            op.amount = amount;
            return apply_op(v, op);
          },
          "at"_a, "color"_a, py::kw_only(), "mode"_a = "blend", "select"_a = "vertex",
          "radius"_a = py::none(), "tolerance"_a = py::none(), "vertices"_a = py::none(),
          "amount"_a = 0.5, "level"_a = 0, "object"_a = py::none());
}

// The building blocks of color and shape edits (edit/selection.h, edit/color.h, edit/shape.h).
void def_edit_parts(PyVectorImage& vi) {
  vi.def(
          "select_colors",
          [](const VectorImage& v, std::array<double, 2> at, const std::string& select,
             std::optional<double> radius, std::optional<double> tolerance, int level) {
            const subvec::ControlMesh& mesh = v.levels[size_t(check_level(v, level))];
            const subvec::Vec2 p = point(at, "at");
            const subvec::EditSelect s = parse_select(select);
            double r = 0, t = 0;
            color_reach(s, radius, tolerance, r, t);
            subvec::ColorSelection sel;
            {
              py::gil_scoped_release release;
              const subvec::MeshTopology topo = subvec::MeshTopology::build(mesh, v.width, v.height);
              sel = subvec::select_colors(mesh, topo, s, p, r, t);
            }
            return py::dict("colors"_a = index_vector(sel.colors), "seed_color"_a = sel.seed_color,
                            "seed_vertex"_a = sel.seed_vertex);
          },
          "at"_a, py::kw_only(), "select"_a = "vertex", "radius"_a = py::none(),
          "tolerance"_a = py::none(), "level"_a = 0)
      .def(
          "blend_colors",
          [](VectorImage& v, const py::object& colors, std::array<double, 3> target, double amount,
             int level) {
            subvec::ControlMesh& mesh = v.levels[size_t(check_level(v, level))];
            const std::vector<int32_t> idx = index_list(colors, mesh.num_colors(), "colors");
            const subvec::Color t = color3(target, "color");
            py::gil_scoped_release release;
            subvec::blend_colors(mesh, idx, t, amount);
          },
          "colors"_a, "color"_a, py::kw_only(), "amount"_a = 0.5, "level"_a = 0)
      .def(
          "transform_colors",
          [](VectorImage& v, const py::object& colors, std::array<double, 3> seed,
             std::array<double, 3> target, int level) {
            subvec::ControlMesh& mesh = v.levels[size_t(check_level(v, level))];
            const std::vector<int32_t> idx = index_list(colors, mesh.num_colors(), "colors");
            const subvec::Color s = color3(seed, "seed"), t = color3(target, "color");
            py::gil_scoped_release release;
            return subvec::transform_colors(mesh, idx, s, t);
          },
          "colors"_a, "seed"_a, "color"_a, py::kw_only(), "level"_a = 0)
      .def(
          "deform",
          [](VectorImage& v, const py::object& vertices, const py::object& targets, double region,
             int level) {
            subvec::ControlMesh& mesh = v.levels[size_t(check_level(v, level))];
            subvec::Handles h;
            h.vertices = index_list(vertices, mesh.num_vertices(), "vertices");
            const auto t = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(targets);
            if (!t) PyErr_Clear();
            if (!t || t.ndim() != 2 || t.shape(1) != 2 || size_t(t.shape(0)) != h.vertices.size()) {
              invalid("targets must have shape (" + std::to_string(h.vertices.size()) + ", 2)");
            }
            for (size_t i = 0; i < h.vertices.size(); ++i) {
              h.targets.push_back({t.data()[2 * i], t.data()[2 * i + 1]});
            }
            h.region = region;
            py::gil_scoped_release release;
            subvec::ShapeEditor editor(mesh, v.width, v.height);
            mesh.positions = editor.deform(h);
            // How far the handles went: 1, or less where the mesh would fold (edit/shape.h).
            return editor.reached();
          },
          "vertices"_a, "targets"_a, py::kw_only(), "region"_a = 0.0, "level"_a = 0);
}

// Stylization, saliency, subdivision, the pyramid's filter and pickling.
void def_analysis(PyVectorImage& vi) {
  // Stylization (edit/stylize.h, apply_stylize): replaces the level's strokes (or, with `object`,
  // that object's) in the region with new ones and reports what it did.
  vi.def(
          "stylize",
          [](VectorImage& v, int level, std::optional<std::array<double, 4>> roi,
             std::optional<double> threshold, uint64_t seed, double probability, std::optional<int> object) {
            check_level(v, level);
            if (object) object_index(v, *object);
            subvec::StylizeOptions options;
            options.level = level;
            options.object = object;
            if (roi) options.roi = subvec::Rect{(*roi)[0], (*roi)[1], (*roi)[2], (*roi)[3]};
            options.threshold = threshold;
            options.seed = seed;
            options.probability = probability;
            subvec::StylizeReport report;
            {
              py::gil_scoped_release release;
              report = subvec::apply_stylize(v, options);
            }
            return py::dict("threshold"_a = report.threshold, "in_region"_a = report.in_region,
                            "above"_a = report.above, "chosen"_a = report.chosen,
                            "strokes"_a = report.strokes, "replaced"_a = report.replaced);
          },
          py::kw_only(), "level"_a = 0, "roi"_a = py::none(), "threshold"_a = py::none(),
          "seed"_a = 1, "probability"_a = 0.3, "object"_a = py::none())
      .def(
          "saliency",
          [](const VectorImage& v, int level) {
            check_level(v, level);
            std::vector<double> s;
            {
              py::gil_scoped_release release;
              s = subvec::feature_saliency(v, level);
            }
            py::array_t<double> out(py::ssize_t(s.size()));
            if (!s.empty()) std::memcpy(out.mutable_data(), s.data(), s.size() * sizeof(double));
            return out;
          },
          py::kw_only(), "level"_a = 0)
      // Subdivision (subdiv/subdivision.h): the refined mesh and the stencil matrices, limit =
      // S @ control. The CSR pieces are wrapped as scipy.sparse matrices by subvec/__init__.py.
      .def(
          "_subdivide",
          [](const VectorImage& v, int level, int depth, bool limit) {
            const subvec::ControlMesh& mesh = v.levels[size_t(check_level(v, level))];
            if (depth < 0 || depth > 6) invalid("depth " + std::to_string(depth) + " is out of range (0 to 6)");
            std::optional<subvec::Subdivision> sub;
            subvec::RefinedMesh refined;
            {
              py::gil_scoped_release release;
              const subvec::MeshTopology topo = subvec::validate_level(mesh, v.width, v.height, level);
              sub.emplace(mesh, topo, depth, std::span<const int32_t>{}, limit);
              sub->evaluate(mesh.positions, mesh.colors, refined);
              sub->position_stencils();
              sub->color_stencils();
            }
            return py::dict(
                "positions"_a = matrix<float>(refined.positions.data(), refined.positions.size() / 2, 2),
                "colors"_a = matrix<float>(refined.colors.data(), refined.colors.size() / 3, 3),
                "triangles"_a = matrix<int32_t>(refined.triangles.data()->data(), refined.triangles.size(), 3),
                "triangle_colors"_a = matrix<int32_t>(refined.triangle_colors.data()->data(),
                                                      refined.triangle_colors.size(), 3),
                "triangle_parent"_a = index_vector(refined.triangle_parent),
                "position_stencils"_a = csr(sub->position_stencils()),
                "color_stencils"_a = csr(sub->color_stencils()));
          },
          py::kw_only(), "level"_a = 0, "depth"_a = 3, "limit"_a = true)
      // Levels of abstraction (pyramid/pyramid.h): a new image with every level (or one object)
      // filtered.
      .def_property_readonly("has_pyramid", [](const VectorImage& v) { return subvec::has_pyramid(v); })
      .def(
          "filter",
          [](const VectorImage& v, std::vector<double> geometry_eta, std::vector<double> color_eta,
             std::optional<int> object) {
            if (object) object_index(v, *object);
            subvec::FilterOptions options;
            options.geometry_eta = std::move(geometry_eta);
            options.color_eta = std::move(color_eta);
            options.object = object;
            py::gil_scoped_release release;
            return subvec::filter(v, options);
          },
          py::kw_only(), "geometry_eta"_a = std::vector<double>{},
          "color_eta"_a = std::vector<double>{}, "object"_a = py::none())
      .def(py::pickle(
          [](const VectorImage& v) {
            subvec::SvecWriteOptions options;
            options.lossless = true;  // a pickle round trip keeps every value
            const std::vector<uint8_t> b = subvec::to_svec_binary(v, options);
            return py::bytes(reinterpret_cast<const char*>(b.data()), b.size());
          },
          [](const py::bytes& state) {
            const std::string s = state;
            return subvec::parse_svec_binary(
                std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(s.data()), s.size()));
          }));
}

// Keyword arguments named as the Python API names them, for the library's field names in
// subvec::validate()'s messages.
std::string keyword_names(const std::string& message) {
  static const std::pair<const char*, const char*> kNames[] = {
      {"levels.levels ", "levels "},
      {"refine.rounds ", "refine "},
      {"fit.relocate_iterations ", "relocate "},
      {"fit.l1_iterations ", "l1_iterations "},
  };
  for (const auto& [field, keyword] : kNames) {
    if (message.rfind(field, 0) == 0) return keyword + message.substr(std::string(field).size());
  }
  return message;
}

// subvec.vectorize(): the keyword arguments fill subvec::VectorizeOptions (defaults and ranges
// are the library's), which makes the document `subvec vectorize` makes, levels included.
void def_vectorize(py::module_& m) {
  const subvec::VectorizeOptions d;
  m.def(
      "vectorize",
      [](const py::object& image, double ratio, int vertices, int levels, int refine, int relocate,
         int l1_iterations, int threads, int64_t max_memory) {
        subvec::VectorizeOptions options;
        options.ratio = ratio;
        options.vertices = vertices;
        options.levels.levels = levels;
        options.refine.rounds = refine;
        options.fit.relocate_iterations = relocate;
        options.fit.l1_iterations = l1_iterations;
        options.threads = threads;
        options.max_memory = max_memory;
        try {
          subvec::validate(options);
        } catch (const Error& e) {
          throw Error(e.code(), keyword_names(e.what()));
        }
        subvec::Image8 img = image_from_array(image);
        py::gil_scoped_release release;
        return subvec::vectorize(img, options);
      },
      "image"_a, py::kw_only(), "ratio"_a = d.ratio, "vertices"_a = d.vertices,
      "levels"_a = d.levels.levels, "refine"_a = d.refine.rounds,
      "relocate"_a = d.fit.relocate_iterations, "l1_iterations"_a = d.fit.l1_iterations,
      "threads"_a = d.threads, "max_memory"_a = d.max_memory);
}

// Files, bytes and raster images.
void def_io(py::module_& m) {
  m.def(
      "load",
      [](const std::filesystem::path& path) {
        py::gil_scoped_release release;
        return subvec::read_svec(path);
      },
      "path"_a);
  m.def(
      "from_bytes",
      [](const py::bytes& data) {
        const std::string s = data;
        py::gil_scoped_release release;
        // As read_svec() tells the forms apart: JSON starts with '{' (after white space),
        // anything else goes to the binary reader, which names wrong magic bytes.
        const size_t first = s.find_first_not_of(" \t\r\n");
        if (first != std::string::npos && s[first] == '{') return subvec::parse_svec_json(s);
        return subvec::parse_svec_binary(
            std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(s.data()), s.size()));
      },
      "data"_a);
  m.def(
      "read_image",
      [](const std::filesystem::path& path, int64_t max_pixels) {
        subvec::Image8 img;
        {
          py::gil_scoped_release release;
          img = subvec::read_image(path, max_pixels);
        }
        return array_from_image(img);
      },
      "path"_a, py::kw_only(), "max_pixels"_a = int64_t{1} << 28);
  m.def(
      "write_png",
      [](const std::filesystem::path& path, const py::array& image) {
        if (image.ndim() != 3 || (image.shape(2) != 3 && image.shape(2) != 4) ||
            !image.dtype().is(py::dtype::of<uint8_t>())) {
          invalid("write_png takes an H x W x 3 or H x W x 4 uint8 array, got shape " +
                  shape_text(image) + " dtype " + py::str(static_cast<py::handle>(image.dtype())).cast<std::string>());
        }
        const auto c = py::array_t<uint8_t, py::array::c_style | py::array::forcecast>::ensure(image);
        subvec::Image8 img(static_cast<int>(c.shape(1)), static_cast<int>(c.shape(0)),
                           static_cast<int>(c.shape(2)));
        std::memcpy(img.pixels.data(), c.data(), img.pixels.size());
        py::gil_scoped_release release;
        subvec::write_png(path, img);
      },
      "path"_a, "image"_a);
  m.def(
      "compare",
      [](const py::object& reference, const py::object& test) {
        const subvec::Image8 a = image_from_array(reference), b = image_from_array(test);
        subvec::ImageDifference d;
        {
          py::gil_scoped_release release;
          d = subvec::compare(a, b);
        }
        return py::dict("mae"_a = py::make_tuple(d.mae[0], d.mae[1], d.mae[2]),
                        "mae_mean"_a = d.mae_mean, "psnr"_a = d.psnr, "ssim"_a = d.ssim);
      },
      "reference"_a, "test"_a);
}

}  // namespace

PYBIND11_MODULE(_subvec, m) {
  m.doc() = "subvec: vector images built on piecewise smooth Loop subdivision surfaces";
  m.attr("__version__") = SUBVEC_VERSION;
  register_exceptions(m);
  PyVectorImage vi(m, "VectorImage",
                   "A subdivision vector image: a control mesh per level of detail over "
                   "a width x height image, with strokes and metadata.");
  def_vector_image(vi);
  def_edits(vi);
  def_edit_parts(vi);
  def_analysis(vi);
  def_vectorize(m);
  def_io(m);
}
