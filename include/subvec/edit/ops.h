// Edit operations as a mouse does them, in image coordinates: the `subvec edit --ops` file
// (docs/editing.md has the format). Parsing checks the file's structure; applying checks what
// needs the image (points inside it, something to select).
#pragma once

#include <array>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "subvec/edit/feature_edit.h"
#include "subvec/edit/selection.h"
#include "subvec/mesh/vector_image.h"

namespace subvec {

enum class ColorMode { kBlend, kTransform };

struct EditOp {
  enum class Kind {
    kDrag,         // from -> to, select vertex (one vertex) or feature (Gaussian falloff, sigma)
    kMoveFeature,  // at; translate, rotate (degrees)
    kColor,        // at; mode, select, radius, tolerance (region), color, amount (blend)
    kMoveVertices, // vertices, translate (the editor's direct handles)
    kAddFeature,   // points, feature_kind (edit/feature_edit.h)
    kDeleteFeature,// at: the nearest feature
    kMakeObject,   // at: the innermost closed tear around it, or rect (make_object_in_rect); name
    kMoveObject,   // object; translate, rotate (degrees), scale, pivot
    kHideObject,   // object
    kShowObject,   // object
    kOrderObject,  // object; to (its new position, 0 the bottom)
  };
  Kind kind = Kind::kDrag;
  int level = 0;
  EditSelect select = EditSelect::kVertex;
  Vec2 from, to;          // drag
  double sigma = 20;      // drag of a feature, pixels
  double region = 0;      // drag, move-feature: deform only within this distance of the handles
  Vec2 at;                // move-feature, color
  Vec2 translate;         // move-feature, pixels
  double rotate = 0;      // move-feature, degrees, clockwise on screen
  ColorMode mode = ColorMode::kBlend;
  double radius = 0;      // color: propagation radius, pixels (a region's cap; infinity: none)
  double tolerance = kDefaultRegionTolerance;  // color of a region: CIELAB distance from the seed
  Color color;            // color: the new color, 0-255
  double amount = 0.5;    // color blend: 0 keeps the old color, 1 paints the new one
  std::vector<int32_t> vertices;  // move-vertices; color with select "vertices"
  std::vector<Vec2> points;       // add-feature: the drawn polyline
  FeatureKind feature_kind = FeatureKind::kTear;  // add-feature
  int object = 0;                 // the object ops: index in VectorImage::objects
  bool in_object = false;         // drag, move-feature, move-vertices, color: edit object `object`'s mesh
  double scale = 1;               // move-object
  std::optional<Vec2> pivot;      // move-object; default the object's centre (object_center)
  int position = 0;               // order-object: the new position ("to" in the file)
  std::string object_name;        // make-object
  std::optional<std::array<int, 4>> rect;  // make-object: x, y, width, height (whole pixels)

  // "drag vertex", "drag feature", "move-feature", "color blend", "color transform",
  // "move-vertices", "add-feature", "delete-feature", "make-object", "move-object", "hide-object",
  // "show-object", "order-object".
  std::string name() const;
};

// Parses an ops file: a JSON array of operation objects. Throws Error(kBadFile) with a one-line
// message naming the operation and the key at fault ("ops[2] (drag): missing key \"to\"").
std::vector<EditOp> parse_edit_ops(std::string_view json);

// Applies the operations in order; returns one line per operation saying what it selected and did.
// Throws Error(kInvalidArgument) naming the operation ("ops[1] (move-feature): ...") when a level
// is out of range, a point lies outside the image, there is nothing to select or a color transform
// is impossible (a shape edit never folds the mesh: one that cannot go all the way stops at its
// last fold-free position and its line says so, edit/shape.h); `image` then holds the operations before the
// failing one.
std::vector<std::string> apply_edit_ops(VectorImage& image, std::span<const EditOp> ops);

}  // namespace subvec
