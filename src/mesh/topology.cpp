#include "subvec/mesh/topology.h"

#include <algorithm>
#include <numeric>
#include <string>

#include "mesh/disjoint_sets_p.h"
#include "subvec/core/error.h"

namespace subvec {
namespace {

int64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (int64_t{a} << 32) | static_cast<uint32_t>(b);
}

[[noreturn]] void fail(const std::string& message) { throw Error(ErrorCode::kInvalidMesh, message); }

std::string edge_name(int a, int b) {
  return "(" + std::to_string(a) + ", " + std::to_string(b) + ")";
}

}  // namespace

int MeshTopology::find_edge(int a, int b) const {
  const int64_t key = edge_key(a, b);
  auto it = std::lower_bound(edge_keys_.begin(), edge_keys_.end(), key);
  return it != edge_keys_.end() && *it == key ? static_cast<int>(it - edge_keys_.begin()) : -1;
}

MeshTopology MeshTopology::build(const ControlMesh& mesh, int width, int height) {
  const int nv = mesh.num_vertices();
  const int nf = mesh.num_triangles();
  MeshTopology t;

  // Edges: sort the 3F directed half-edges by undirected key; each key must occur once (border) or
  // twice with opposite directions (interior, consistently oriented).
  struct HalfEdge {
    int64_t key;
    int32_t face;
    int8_t corner;
  };
  std::vector<HalfEdge> half(size_t(nf) * 3);
  for (int f = 0; f < nf; ++f) {
    const Tri& tri = mesh.triangles[f];
    for (int k = 0; k < 3; ++k) {
      const int a = tri[k], b = tri[(k + 1) % 3];
      if (a < 0 || a >= nv) {
        fail("triangle " + std::to_string(f) + " refers to vertex " + std::to_string(a) +
             ", out of range (" + std::to_string(nv) + " vertices)");
      }
      if (a == b) fail("triangle " + std::to_string(f) + " repeats vertex " + std::to_string(a));
      half[size_t(f) * 3 + k] = {edge_key(a, b), f, static_cast<int8_t>(k)};
    }
  }
  // Order by (key, face): a counting sort on the smaller vertex (stable, so faces stay in order),
  // then each vertex's handful of half-edges by the larger one.
  {
    std::vector<int32_t> start(size_t(nv) + 1, 0);
    for (const HalfEdge& h : half) ++start[(h.key >> 32) + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    std::vector<HalfEdge> sorted(half.size());
    std::vector<int32_t> fill(start.begin(), start.end() - 1);
    for (const HalfEdge& h : half) sorted[fill[h.key >> 32]++] = h;
    for (int v = 0; v < nv; ++v) {
      if (start[v + 1] - start[v] < 2) continue;  // (also: no pointer arithmetic on an empty array)
      HalfEdge* first = sorted.data() + start[v];
      HalfEdge* last = sorted.data() + start[v + 1];
      for (HalfEdge* i = first + 1; i < last; ++i) {  // stable insertion sort by key
        const HalfEdge h = *i;
        HalfEdge* j = i;
        for (; j > first && (j - 1)->key > h.key; --j) *j = *(j - 1);
        *j = h;
      }
    }
    half = std::move(sorted);
  }

  t.face_edges.assign(nf, {-1, -1, -1});
  for (size_t i = 0; i < half.size();) {
    size_t j = i;
    while (j < half.size() && half[j].key == half[i].key) ++j;
    const int a = static_cast<int>(half[i].key >> 32), b = static_cast<int>(half[i].key & 0xffffffff);
    if (j - i > 2) fail("edge " + edge_name(a, b) + " is shared by more than two triangles");
    const int e = static_cast<int>(t.edges.size());
    t.edges.push_back({a, b});
    t.edge_keys_.push_back(half[i].key);
    std::array<int32_t, 2> faces{half[i].face, -1};
    if (j - i == 2) {
      faces[1] = half[i + 1].face;
      const Tri& f0 = mesh.triangles[half[i].face];
      const Tri& f1 = mesh.triangles[half[i + 1].face];
      if (f0[half[i].corner] == f1[half[i + 1].corner]) {
        fail("triangles " + std::to_string(faces[0]) + " and " + std::to_string(faces[1]) +
             " are oriented inconsistently across edge " + edge_name(a, b));
      }
    }
    t.edge_faces.push_back(faces);
    for (size_t h = i; h < j; ++h) t.face_edges[half[h].face][half[h].corner] = e;
    i = j;
  }

  // Vertex -> face incidence (CSR).
  t.vertex_face_offsets.assign(size_t(nv) + 1, 0);
  for (const Tri& tri : mesh.triangles)
    for (int v : tri) ++t.vertex_face_offsets[v + 1];
  std::partial_sum(t.vertex_face_offsets.begin(), t.vertex_face_offsets.end(),
                   t.vertex_face_offsets.begin());
  t.vertex_faces.resize(size_t(nf) * 3);
  {
    std::vector<int32_t> fill(t.vertex_face_offsets.begin(), t.vertex_face_offsets.end() - 1);
    for (int f = 0; f < nf; ++f)
      for (int v : mesh.triangles[f]) t.vertex_faces[fill[v]++] = f;
  }

  // Edge tags: border from adjacency, then creases, then feature edges (tears).
  t.edge_tags.assign(t.edges.size(), EdgeTag::kSmooth);
  for (size_t e = 0; e < t.edges.size(); ++e)
    if (t.edge_faces[e][1] < 0) t.edge_tags[e] = EdgeTag::kBorder;

  auto tag_interior_edge = [&](int a, int b, EdgeTag tag, const std::string& what) {
    if (a < 0 || a >= nv || b < 0 || b >= nv) {
      fail(what + " refers to vertex " + std::to_string(a < 0 || a >= nv ? a : b) +
           ", out of range (" + std::to_string(nv) + " vertices)");
    }
    const int e = t.find_edge(a, b);
    if (e < 0) fail(what + ": " + edge_name(a, b) + " is not an edge of the mesh");
    if (t.edge_tags[e] == EdgeTag::kBorder) fail(what + ": " + edge_name(a, b) + " lies on the image border");
    if (t.edge_tags[e] != EdgeTag::kSmooth) {
      fail(what + ": edge " + edge_name(a, b) + " is already a " +
           (t.edge_tags[e] == EdgeTag::kTear ? "feature edge" : "crease"));
    }
    t.edge_tags[e] = tag;
  };
  for (size_t i = 0; i < mesh.creases.size(); ++i) {
    tag_interior_edge(mesh.creases[i][0], mesh.creases[i][1], EdgeTag::kCrease,
                      "crease " + std::to_string(i));
  }
  std::vector<uint8_t> is_endpoint(nv, 0);
  for (size_t i = 0; i < mesh.features.size(); ++i) {
    const Feature& feature = mesh.features[i];
    const std::string what = "feature " + std::to_string(i) + " (id " + std::to_string(feature.id) + ")";
    if (feature.vertices.size() < 2) fail(what + " has fewer than two vertices");
    for (size_t k = 0; k + 1 < feature.vertices.size(); ++k)
      tag_interior_edge(feature.vertices[k], feature.vertices[k + 1], EdgeTag::kTear, what);
    if (!feature.closed()) {
      is_endpoint[feature.vertices.front()] = 1;
      is_endpoint[feature.vertices.back()] = 1;
    }
  }

  // Vertex tags (paper §3.2).
  std::vector<uint8_t> creases(nv, 0), tears(nv, 0);
  for (size_t e = 0; e < t.edges.size(); ++e) {
    const EdgeTag tag = t.edge_tags[e];
    if (tag == EdgeTag::kSmooth) continue;
    auto& count = tag == EdgeTag::kTear ? tears : creases;
    for (int v : t.edges[e]) count[v] = static_cast<uint8_t>(std::min(count[v] + 1, 255));
  }
  t.vertex_tags.assign(nv, VertexTag::kSmooth);
  for (int v = 0; v < nv; ++v) {
    const Vec2 p = mesh.positions[v];
    const bool image_corner =
        width >= 0 && (p.x == 0 || p.x == width) && (p.y == 0 || p.y == height);
    if (image_corner || is_endpoint[v]) {
      t.vertex_tags[v] = VertexTag::kCorner;
    } else if (creases[v] == 0 && tears[v] == 0) {
      t.vertex_tags[v] = VertexTag::kSmooth;
    } else if (creases[v] == 2 && tears[v] == 0) {
      t.vertex_tags[v] = VertexTag::kCrease;
    } else if (tears[v] == 2 && creases[v] == 0) {
      t.vertex_tags[v] = VertexTag::kTear;
    } else {
      t.vertex_tags[v] = VertexTag::kCorner;
    }
  }
  return t;
}

std::vector<Tri> face_varying_indices(const ControlMesh& mesh, const MeshTopology& topo, int& num_colors) {
  const int nf = mesh.num_triangles();
  detail::DisjointSets corners(size_t(nf) * 3);  // over the 3F corners
  auto corner = [&](int f, int v) {
    for (int k = 0; k < 3; ++k)
      if (mesh.triangles[f][k] == v) return f * 3 + k;
    return -1;
  };
  for (int e = 0; e < topo.num_edges(); ++e) {
    const auto [f, g] = topo.edge_faces[e];
    if (g < 0 || topo.edge_tags[e] == EdgeTag::kTear) continue;
    for (int v : topo.edges[e]) corners.unite(corner(f, v), corner(g, v));
  }
  std::vector<int32_t> index(size_t(nf) * 3, -1);
  std::vector<Tri> out(nf);
  num_colors = 0;
  for (int c = 0; c < nf * 3; ++c) {
    int32_t& id = index[corners.find(c)];
    if (id < 0) id = num_colors++;
    out[c / 3][c % 3] = id;
  }
  return out;
}

}  // namespace subvec
