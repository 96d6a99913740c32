// Derived topology of a ControlMesh: the edge list with tags, edge-face adjacency and the vertex
// types of paper §3.2. Built once per mesh (O(#F log #F)) and never mutated; rebuild it when the
// mesh connectivity changes.
#pragma once

#include <cstdint>
#include <vector>

#include "subvec/mesh/vector_image.h"

namespace subvec {

enum class EdgeTag : uint8_t {
  kSmooth,
  kCrease,  // an interior crease listed in ControlMesh::creases
  kTear,    // an edge of a feature: geometrically a crease, color discontinuous across it
  kBorder,  // on the image border: a crease with one side
};

// Paper §3.2: smooth = only smooth edges; crease/tear = exactly two crease/tear edges (border
// edges count as creases); corner = everything else, including feature endpoints, junctions of
// three or more sharp edges, a tear meeting a crease, and the four image corners.
enum class VertexTag : uint8_t { kSmooth, kCrease, kTear, kCorner };

inline bool is_sharp(EdgeTag t) { return t != EdgeTag::kSmooth; }

struct MeshTopology {
  std::vector<EdgeVerts> edges;                  // #E, each with a < b
  std::vector<std::array<int32_t, 2>> edge_faces;  // #E; second is -1 on the border
  std::vector<std::array<int32_t, 3>> face_edges;  // #F; k-th is the edge (v_k, v_{k+1})
  std::vector<EdgeTag> edge_tags;                // #E
  std::vector<VertexTag> vertex_tags;            // #V
  std::vector<int32_t> vertex_face_offsets;      // #V+1, CSR of vertex -> incident faces
  std::vector<int32_t> vertex_faces;

  int num_edges() const { return static_cast<int>(edges.size()); }
  // Index of edge (a, b) in either order, or -1.
  int find_edge(int a, int b) const;
  // Faces incident to vertex v (unordered).
  std::pair<const int32_t*, const int32_t*> faces_of(int v) const {
    return {vertex_faces.data() + vertex_face_offsets[v],
            vertex_faces.data() + vertex_face_offsets[v + 1]};
  }

  // Builds the topology. Throws Error(kInvalidMesh) when indices are out of range, the mesh is not
  // an edge-manifold consistently oriented triangle mesh, or a crease/feature is not a chain of
  // mesh edges. Geometric checks are in validate(). The vertices at the corners of the width x height
  // image are corners; an object's mesh (Object) has none: pass kNoFrame for both.
  static constexpr int kNoFrame = -1;
  static MeshTopology build(const ControlMesh& mesh, int width, int height);

 private:
  std::vector<int64_t> edge_keys_;  // sorted (a << 32 | b), parallel to edges
};

// Face-varying color indices implied by the tears: the corners of a vertex share one color index
// unless a tear separates them (a union over every non-tear interior edge). Returns #F index
// triples numbered in order of first use, and sets `num_colors`.
std::vector<Tri> face_varying_indices(const ControlMesh& mesh, const MeshTopology& topology, int& num_colors);

}  // namespace subvec
