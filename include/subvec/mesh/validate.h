// Validation of a vector image: everything a reader, an editor or a renderer relies on.
#pragma once

#include <vector>

#include "subvec/mesh/topology.h"
#include "subvec/mesh/vector_image.h"

namespace subvec {

// Hard limits on what subvec accepts from a file (docs/format.md lists them).
struct Limits {
  static constexpr int32_t kMaxDimension = 1 << 16;         // width or height, pixels
  static constexpr int64_t kMaxPixels = int64_t{1} << 30;   // width * height
  static constexpr int32_t kMaxLevels = 64;
  static constexpr int32_t kMaxObjects = 4096;
  static constexpr int64_t kMaxElements = int64_t{1} << 26; // vertices, colors, triangles per level
};

// Checks one level against the image size and returns its topology. Throws Error(kInvalidMesh)
// with a one-line message naming the level, the element and its index:
//  - sizes within Limits; positions and colors finite; positions inside the domain;
//  - triangles with valid, distinct indices and positive signed area (not flipped or degenerate);
//  - an edge-manifold mesh with no unused vertex, whose boundary lies on the image border and
//    whose triangles tile the domain exactly (no gap, no overlap; the 4 image corners are vertices);
//  - creases and features are chains of interior mesh edges, each edge in at most one of them;
//  - colors: each color value belongs to one vertex and is used; corners across a non-tear edge
//    use the same color values.
MeshTopology validate_level(const ControlMesh& mesh, int width, int height, int level_index = 0);

// Checks object `index` of an image of width x height pixels with `num_levels` levels and returns
// its topology (built with MeshTopology::kNoFrame). As validate_level, except that the mesh need
// not tile the image: its boundary is one or more closed loops of edges (each boundary vertex on
// exactly two boundary edges), the triangles around each interior vertex make one full turn, and
// positions may leave the image (within +-2^24 px). Messages start with "object N: ".
MeshTopology validate_object(const Object& object, int width, int height, int num_levels, int index);

// The visible objects drawn over `level`, bottom to top, each checked by validate_object: their
// indices in image.objects and their topologies. What every drawing of the objects starts from.
struct ObjectTopology {
  int object = 0;
  MeshTopology topology;
};
std::vector<ObjectTopology> visible_objects(const VectorImage& image, int level);

// Checks the whole image: size, levels (at least one), every level, objects and strokes.
void validate(const VectorImage& image);

}  // namespace subvec
