// Objects as layers (issue 26; the paper's own limitation, §7.3: "the vector image is one mesh").
//
// Making an object. A closed tear of a level (a GrabCut boundary from `--segment`, a feature the
// user drew, a detected one) bounds a region of the level's control mesh. make_object cuts the mesh
// along it:
//  - the object (Object, mesh/vector_image.h) gets the region's triangles, vertices and inside
//    colors, and the features and creases within it. Its boundary is the closed curve, so it
//    renders as the region did: the inner colors depend on nothing outside the tear;
//  - the level keeps the rest, and under the object a background is completed. The region's
//    triangles stay (without their features and creases) and are simplified to the level's mean
//    vertex density by half-edge collapses; their colors are the smoothest fill from the ring
//    around the hole: a thin plate (the squared uniform Laplacian over the hole's vertices and the
//    curve's, biharmonic) whose values on the curve are pulled to the colors just outside it, a
//    control edge off the tear, robustly, so that a stray color on the rim does not bend the
//    fill. The closed curve stays a tear of the level, so nothing outside the hole changes.
// A feature that crosses the curve at one of its vertices is split there, each side's part going
// to its side. The level's strokes with at least half their points inside the curve's control
// polygon go to the object (Object::strokes): they belong to what they were drawn on.
//
// Editing an object. Its control points move rigidly (move, rotate, scale about a pivot): the
// limit surface of an affine image of the control points is the same affine image of the limit
// surface, so the object moves exactly, and its strokes with it. It can be hidden, shown and reordered; objects draw over
// their level in the order of VectorImage::objects, each anti-aliased along its boundary.
//
// Every function validates what it is given and throws Error(kInvalidArgument) naming the problem
// with the image unchanged. All are deterministic.
#pragma once

#include <optional>
#include <string>

#include "subvec/mesh/vector_image.h"
#include "subvec/vectorize/segment.h"

namespace subvec {

struct MakeObjectResult {
  int object = -1;          // index of the new object in image.objects
  int object_vertices = 0;  // control vertices of the object
  int fill_vertices = 0;    // interior vertices of the background under it (after simplification)
  int removed = 0;          // hole vertices removed by the simplification
  int features_moved = 0;   // features (or parts of features) that went into the object
  int strokes_moved = 0;    // strokes of the level that went into the object
  // make_object_in_rect: the outline follows the control edges round GrabCut's foreground (its
  // fitted curve could not be cut in), not the curve.
  bool along_edges = false;
};

// Makes an object of the region that feature `feature` (a closed tear of level `level`) bounds.
// Throws Error(kInvalidArgument) when the level or feature is out of range, the feature is open
// or repeats a vertex, or the region it bounds touches the image border.
MakeObjectResult make_object(VectorImage& image, int level, int feature, const std::string& name = "");

// Makes an object of what `rect` frames on level `level` (the editor's rectangle): the largest
// closed tear whose control polygon lies inside the rectangle and covers a fifth of it at least;
// or, when none does, the foreground
// GrabCut finds in the rectangle on the level's render (segment_foreground, vectorize/segment.h),
// whose boundary is first cut into the level as a closed tear (add_feature, edit/feature_edit.h:
// it meets the features it crosses at junctions, and the object's curve is then made of the
// pieces between them). Where add_feature refuses that curve (it runs along features at a
// glancing angle), the outline is the cycle of control edges round the faces whose centroid the
// foreground holds, made a tear where it is not one (MakeObjectResult::along_edges). Throws
// Error(kInvalidArgument), the image unchanged, for a rectangle GrabCut cannot use, or a
// foreground that reaches the image border or leaves no faces.
MakeObjectResult make_object_in_rect(VectorImage& image, int level, const PixelRect& rect,
                                     const std::string& name = "");

// The innermost closed tear of `mesh` around point p: the feature whose control polygon encloses
// p with the smallest area (the limit curve lies within a fraction of a control edge of it), or
// -1 when none does.
int closed_feature_around(const ControlMesh& mesh, Vec2 p);

// A similarity transform about `pivot` (default: the centre of the object's control points'
// bounding box): scale, then rotate by `rotate_degrees` (clockwise on screen, y down, as SVG's
// rotate()), then translate.
struct ObjectTransform {
  Vec2 translate = {};
  double rotate_degrees = 0;
  double scale = 1;
  std::optional<Vec2> pivot = std::nullopt;
};

// Applies `transform` to object `object`'s control points and its strokes' points (their widths
// scaled by `scale`). Throws Error(kInvalidArgument) for an
// index out of range, a non-finite value or a scale that is not positive.
void transform_object(VectorImage& image, int object, const ObjectTransform& transform);

// Shows or hides object `object`.
void set_object_visible(VectorImage& image, int object, bool visible);

// Moves object `object` to position `to` of the drawing order (0 is the bottom), shifting the
// ones between.
void reorder_object(VectorImage& image, int object, int to);

// The pivot transform_object uses by default: the centre of the object's control bounding box.
Vec2 object_center(const Object& object);

}  // namespace subvec
