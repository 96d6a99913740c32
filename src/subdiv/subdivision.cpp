// OpenSubdiv adapter: ControlMesh -> Far::TopologyRefiner (Loop, tags from MeshTopology), uniform
// refinement plus limit push for rendering and fitting, and adaptive patches for exact evaluation.
#include "subvec/subdiv/subdivision.h"

#include <algorithm>
#include <numeric>
#include <string>

#include <opensubdiv/far/patchMap.h>
#include <opensubdiv/far/patchTable.h>
#include <opensubdiv/far/patchTableFactory.h>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/stencilTable.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefiner.h>
#include <opensubdiv/far/topologyRefinerFactory.h>

#include "core/parallel_p.h"
#include "subvec/core/error.h"

namespace subvec {

namespace Far = OpenSubdiv::Far;
namespace Sdc = OpenSubdiv::Sdc;

namespace {

// Primvar buffers for Far::PrimvarRefinerReal<double>: N doubles with Clear / AddWithWeight.
template <int N>
struct Value {
  double v[N];
  void Clear(void* = nullptr) { std::fill(v, v + N, 0.0); }
  void AddWithWeight(const Value& src, double weight) {
    for (int i = 0; i < N; ++i) v[i] += weight * src.v[i];
  }
};
using Value2 = Value<2>;
using Value3 = Value<3>;

// Primvar stand-ins that record weights instead of values: reading vertex j yields "unit j", and
// the destination row collects (j, weight) triplets. Used to turn the refinement and limit masks
// into matrices.
struct UnitRef {
  int index;
};
struct UnitSource {
  UnitRef operator[](int i) const { return {i}; }
};
struct TripletRow {
  std::vector<Eigen::Triplet<double, int32_t>>* triplets;
  int row;
  void Clear(void* = nullptr) {}
  void AddWithWeight(const UnitRef& src, double weight) {
    if (weight != 0) triplets->emplace_back(row, src.index, weight);
  }
  // Face-varying refinement of quad schemes reads back values it has just written (face points);
  // the Loop scheme never does.
  void AddWithWeight(const TripletRow&, double) {
    throw Error(ErrorCode::kInvalidArgument, "stencils: a mask refers to a refined value (not a Loop mask)");
  }
};
struct TripletSink {
  std::vector<Eigen::Triplet<double, int32_t>>* triplets;
  TripletRow operator[](int i) const { return {triplets, i}; }
};

// The sub-mesh that a set of control faces needs: the faces themselves first, then every other
// face sharing a vertex with them. The limit surface over a face depends only on the control
// vertices of that one-ring, and every rule applied near the selected faces sees complete
// neighbourhoods, so refining the sub-mesh gives exact values over the selected faces.
struct SubMesh {
  std::vector<int32_t> faces;          // local face -> control face
  int num_selected = 0;                // faces[0 .. num_selected) are the selected ones
  std::vector<int32_t> vertices;       // local vertex -> control vertex
  std::vector<int32_t> colors;         // local color -> control color
  std::vector<int32_t> local_tris;     // 3 per local face
  std::vector<int32_t> local_tri_colors;
};

SubMesh make_submesh(const ControlMesh& mesh, const MeshTopology& topo,
                     std::span<const int32_t> selected) {
  SubMesh s;
  const int nf = mesh.num_triangles();
  if (selected.empty()) {
    s.faces.resize(nf);
    std::iota(s.faces.begin(), s.faces.end(), 0);
    s.num_selected = nf;
  } else {
    std::vector<uint8_t> mark(nf, 0);
    for (int32_t f : selected) {
      if (f < 0 || f >= nf) throw Error(ErrorCode::kInvalidArgument, "face " + std::to_string(f) + " out of range");
      if (!mark[f]) s.faces.push_back(f);
      mark[f] = 1;
    }
    s.num_selected = static_cast<int>(s.faces.size());
    for (int i = 0; i < s.num_selected; ++i) {
      for (int v : mesh.triangles[s.faces[i]]) {
        auto [begin, end] = topo.faces_of(v);
        for (const int32_t* g = begin; g != end; ++g) {
          if (!mark[*g]) {
            mark[*g] = 2;
          }
        }
      }
    }
    for (int f = 0; f < nf; ++f)
      if (mark[f] == 2) s.faces.push_back(f);
  }

  if (selected.empty()) {
    // The whole (validated) mesh: local indices are control indices (until make_refiner
    // renumbers the colors).
    s.vertices.resize(mesh.num_vertices());
    std::iota(s.vertices.begin(), s.vertices.end(), 0);
    s.colors.resize(mesh.num_colors());
    std::iota(s.colors.begin(), s.colors.end(), 0);
    for (int f = 0; f < nf; ++f) {
      s.local_tris.insert(s.local_tris.end(), mesh.triangles[f].begin(), mesh.triangles[f].end());
      s.local_tri_colors.insert(s.local_tri_colors.end(), mesh.triangle_colors[f].begin(),
                                mesh.triangle_colors[f].end());
    }
    return s;
  }
  std::vector<int32_t> vmap(mesh.num_vertices(), -1), cmap(mesh.num_colors(), -1);
  s.local_tris.reserve(s.faces.size() * 3);
  s.local_tri_colors.reserve(s.faces.size() * 3);
  for (int32_t f : s.faces) {
    for (int k = 0; k < 3; ++k) {
      int32_t& lv = vmap[mesh.triangles[f][k]];
      if (lv < 0) {
        lv = static_cast<int32_t>(s.vertices.size());
        s.vertices.push_back(mesh.triangles[f][k]);
      }
      int32_t& lc = cmap[mesh.triangle_colors[f][k]];
      if (lc < 0) {
        lc = static_cast<int32_t>(s.colors.size());
        s.colors.push_back(mesh.triangle_colors[f][k]);
      }
      s.local_tris.push_back(lv);
      s.local_tri_colors.push_back(lc);
    }
  }
  return s;
}

// Builds the Loop refiner of a sub-mesh: sharp edges (creases and tears) and corner vertices
// infinitely sharp; the image border is the mesh boundary (implicitly sharp); colors are
// face-varying channel 0, seams wherever the color indices differ (tears), smooth up to the seams.
std::unique_ptr<Far::TopologyRefiner> create_refiner(const ControlMesh& mesh,
                                                     const MeshTopology& topo, const SubMesh& s) {
  std::vector<int32_t> creases;
  std::vector<uint8_t> seen(topo.num_edges(), 0);
  for (int32_t f : s.faces) {
    for (int k = 0; k < 3; ++k) {
      const int e = topo.face_edges[f][k];
      if (seen[e]) continue;
      seen[e] = 1;
      const EdgeTag tag = topo.edge_tags[e];
      if (tag == EdgeTag::kCrease || tag == EdgeTag::kTear) {
        creases.push_back(mesh.triangles[f][k]);
        creases.push_back(mesh.triangles[f][(k + 1) % 3]);
      }
    }
  }
  std::vector<int32_t> local_of(mesh.num_vertices(), -1);
  for (size_t i = 0; i < s.vertices.size(); ++i) local_of[s.vertices[i]] = static_cast<int32_t>(i);
  for (int32_t& v : creases) v = local_of[v];
  std::vector<int32_t> corners;
  for (size_t i = 0; i < s.vertices.size(); ++i)
    if (topo.vertex_tags[s.vertices[i]] == VertexTag::kCorner) corners.push_back(static_cast<int32_t>(i));

  const std::vector<float> crease_weights(creases.size() / 2, Sdc::Crease::SHARPNESS_INFINITE);
  const std::vector<float> corner_weights(corners.size(), Sdc::Crease::SHARPNESS_INFINITE);
  const std::vector<int> verts_per_face(s.faces.size(), 3);

  Far::TopologyDescriptor desc;
  desc.numVertices = static_cast<int>(s.vertices.size());
  desc.numFaces = static_cast<int>(s.faces.size());
  desc.numVertsPerFace = verts_per_face.data();
  desc.vertIndicesPerFace = s.local_tris.data();
  desc.numCreases = static_cast<int>(creases.size() / 2);
  desc.creaseVertexIndexPairs = creases.data();
  desc.creaseWeights = crease_weights.data();
  desc.numCorners = static_cast<int>(corners.size());
  desc.cornerVertexIndices = corners.data();
  desc.cornerWeights = corner_weights.data();
  Far::TopologyDescriptor::FVarChannel channel;
  channel.numValues = static_cast<int>(s.colors.size());
  channel.valueIndices = s.local_tri_colors.data();
  desc.numFVarChannels = 1;
  desc.fvarChannels = &channel;

  Sdc::Options sdc;
  sdc.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_ONLY);
  sdc.SetFVarLinearInterpolation(Sdc::Options::FVAR_LINEAR_NONE);
  using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
  std::unique_ptr<Far::TopologyRefiner> refiner(
      Factory::Create(desc, Factory::Options(Sdc::SCHEME_LOOP, sdc)));
  if (!refiner) throw Error(ErrorCode::kInvalidMesh, "OpenSubdiv rejected the control mesh topology");
  return refiner;
}

// Workaround for OpenSubdiv 3.5: on an unrefined level, PrimvarRefiner::LimitFaceVarying looks
// up face-varying value tags by value index (FVarLevel::getValueTag), but they are stored per
// (vertex, sibling) slot: vertex by vertex in index order, each vertex's values in the order they
// first appear around it. The two agree only when the values are numbered that way; otherwise the
// limit of a depth-0 Subdivision takes the wrong rule for colors near tears (a smooth value gets a
// crease mask, a tear value is held fixed). Refined levels are numbered by OpenSubdiv and are
// fine. So number the sub-mesh's color values in slot order, rebuilding the refiner if needed.
std::unique_ptr<Far::TopologyRefiner> make_refiner(const ControlMesh& mesh,
                                                   const MeshTopology& topo, SubMesh& s) {
  std::unique_ptr<Far::TopologyRefiner> refiner = create_refiner(mesh, topo, s);
  const Far::TopologyLevel& base = refiner->GetLevel(0);
  std::vector<int32_t> slot(s.colors.size(), -1);
  int32_t next = 0;
  for (int v = 0; v < base.GetNumVertices(); ++v) {
    const auto faces = base.GetVertexFaces(v);
    const auto corners = base.GetVertexFaceLocalIndices(v);
    for (int i = 0; i < faces.size(); ++i) {
      int32_t& value_slot = slot[base.GetFaceFVarValues(faces[i], 0)[corners[i]]];
      if (value_slot < 0) value_slot = next++;
    }
  }
  for (int32_t& value_slot : slot)
    if (value_slot < 0) value_slot = next++;  // unused values (not in a validated mesh) go last
  bool identity = true;
  for (size_t i = 0; i < slot.size(); ++i) identity &= slot[i] == static_cast<int32_t>(i);
  if (identity) return refiner;
  std::vector<int32_t> colors(s.colors.size());
  for (size_t i = 0; i < slot.size(); ++i) colors[slot[i]] = s.colors[i];
  s.colors = std::move(colors);
  for (int32_t& c : s.local_tri_colors) c = slot[c];
  return create_refiner(mesh, topo, s);
}

using detail::parallel_for;
using detail::resolve_threads;

}  // namespace

struct Subdivision::Impl {
  int depth = 0;
  bool push_to_limit = true;
  int num_control_vertices = 0, num_control_colors = 0;
  SubMesh sub;
  std::unique_ptr<Far::TopologyRefiner> refiner;
  RefinedMesh topology;                // triangles, tags; indices into the compact output
  std::vector<int32_t> out_vertices;   // output vertex -> last-level vertex
  std::vector<int32_t> out_colors;     // output color -> last-level fvar value
  mutable SparseMatrix position_stencils, color_stencils;
  mutable bool have_position_stencils = false, have_color_stencils = false;
  // Meshes up to this many output rows evaluate through the limit stencils (built on first use,
  // then one sparse product per evaluation, split over threads); larger ones refine level by
  // level, which needs no stencil memory. The choice depends on the size alone, so a given
  // Subdivision always computes the same numbers.
  static constexpr size_t kMaxStencilRows = size_t{1} << 19;
  bool use_stencils() const { return out_vertices.size() + out_colors.size() <= kMaxStencilRows; }

  // Refines N channels of data; writes channel c of output value i to out[i * stride + offset + c].
  template <int N, bool FaceVarying, class Gather>
  void refine_and_limit(Gather gather, std::span<float> out, int stride = N, int offset = 0) const;
  // Level-by-level evaluation, never through the stencils.
  void refine_positions(std::span<const Vec2> positions, std::span<float> out) const;
  void refine_colors(std::span<const Color> colors, std::span<float> out, int threads) const;
  SparseMatrix limit_stencils(bool face_varying) const;
};

Subdivision::Subdivision(const ControlMesh& mesh, const MeshTopology& topo, int depth,
                         std::span<const int32_t> faces, bool push_to_limit)
    : impl_(std::make_unique<Impl>()) {
  if (depth < 0 || depth > 10) {
    throw Error(ErrorCode::kInvalidArgument, "subdivision depth " + std::to_string(depth) + " out of range 0..10");
  }
  Impl& m = *impl_;
  m.depth = depth;
  m.push_to_limit = push_to_limit;
  m.num_control_vertices = mesh.num_vertices();
  m.num_control_colors = mesh.num_colors();
  m.sub = make_submesh(mesh, topo, faces);
  m.refiner = make_refiner(mesh, topo, m.sub);
  if (depth > 0) {
    Far::TopologyRefiner::UniformOptions options(depth);
    options.fullTopologyInLastLevel = true;
    m.refiner->RefineUniform(options);
  }

  // Edge tags of the sub-mesh's base edges, then inherited by child edges level by level.
  std::vector<EdgeTag> tags;
  {
    const Far::TopologyLevel& base = m.refiner->GetLevel(0);
    tags.resize(base.GetNumEdges());
    for (int e = 0; e < base.GetNumEdges(); ++e) {
      auto ev = base.GetEdgeVertices(e);
      tags[e] = topo.edge_tags[topo.find_edge(m.sub.vertices[ev[0]], m.sub.vertices[ev[1]])];
    }
  }
  // Ancestor of each face among the base faces, to keep the children of selected faces only.
  std::vector<int32_t> ancestor(m.sub.faces.size()), parent_ancestor;
  std::iota(ancestor.begin(), ancestor.end(), 0);
  for (int level = 1; level <= depth; ++level) {
    const Far::TopologyLevel& parent = m.refiner->GetLevel(level - 1);
    const Far::TopologyLevel& child = m.refiner->GetLevel(level);
    std::vector<EdgeTag> child_tags(child.GetNumEdges(), EdgeTag::kSmooth);
    for (int e = 0; e < parent.GetNumEdges(); ++e) {
      if (tags[e] == EdgeTag::kSmooth) continue;
      for (int c : parent.GetEdgeChildEdges(e)) child_tags[c] = tags[e];
    }
    tags = std::move(child_tags);
    std::vector<int32_t> child_ancestor(child.GetNumFaces());
    for (int f = 0; f < child.GetNumFaces(); ++f) child_ancestor[f] = ancestor[child.GetFaceParentFace(f)];
    if (level == depth) parent_ancestor = std::move(ancestor);
    ancestor = std::move(child_ancestor);
  }

  const Far::TopologyLevel& last = m.refiner->GetLevel(depth);
  std::vector<int32_t> vmap(last.GetNumVertices(), -1), cmap(last.GetNumFVarValues(0), -1);
  RefinedMesh& r = m.topology;
  r.depth = depth;
  std::vector<uint8_t> edge_done(last.GetNumEdges(), 0);
  for (int f = 0; f < last.GetNumFaces(); ++f) {
    if (ancestor[f] >= m.sub.num_selected) continue;
    auto fv = last.GetFaceVertices(f);
    auto fc = last.GetFaceFVarValues(f, 0);
    Tri tri, tri_colors;
    for (int k = 0; k < 3; ++k) {
      int32_t& v = vmap[fv[k]];
      if (v < 0) {
        v = static_cast<int32_t>(m.out_vertices.size());
        m.out_vertices.push_back(fv[k]);
      }
      int32_t& c = cmap[fc[k]];
      if (c < 0) {
        c = static_cast<int32_t>(m.out_colors.size());
        m.out_colors.push_back(fc[k]);
      }
      tri[k] = v;
      tri_colors[k] = c;
    }
    r.triangles.push_back(tri);
    r.triangle_colors.push_back(tri_colors);
    r.triangle_parent.push_back(m.sub.faces[ancestor[f]]);
    for (int e : last.GetFaceEdges(f)) {
      if (edge_done[e] || tags[e] == EdgeTag::kSmooth) continue;
      edge_done[e] = 1;
      auto ev = last.GetEdgeVertices(e);
      const EdgeVerts edge{vmap[ev[0]], vmap[ev[1]]};
      if (edge[0] < 0 || edge[1] < 0) {  // both ends are vertices of face f: always mapped
        edge_done[e] = 0;
        continue;
      }
      (tags[e] == EdgeTag::kTear ? r.tear_edges
       : tags[e] == EdgeTag::kCrease ? r.crease_edges
                                     : r.border_edges).push_back(edge);
    }
  }
  // The surface one level coarser over the same vertices: each face of level depth - 1 as the
  // child vertices of its corners (their limit points are the coarser level's), each with the
  // color value it has in the face's children.
  if (depth > 0) {
    const Far::TopologyLevel& parent = m.refiner->GetLevel(depth - 1);
    for (int pf = 0; pf < parent.GetNumFaces(); ++pf) {
      if (parent_ancestor[pf] >= m.sub.num_selected) continue;
      auto corners = parent.GetFaceVertices(pf);
      auto children = parent.GetFaceChildFaces(pf);
      Tri tri{-1, -1, -1}, tri_colors{-1, -1, -1};
      for (int k = 0; k < 3; ++k) {
        const int cv = parent.GetVertexChildVertex(corners[k]);
        tri[k] = vmap[cv];
        for (int cf : children) {
          auto fv = last.GetFaceVertices(cf);
          for (int j = 0; j < 3 && tri_colors[k] < 0; ++j) {
            if (fv[j] == cv) tri_colors[k] = cmap[last.GetFaceFVarValues(cf, 0)[j]];
          }
        }
      }
      r.coarse_triangles.push_back(tri);
      r.coarse_triangle_colors.push_back(tri_colors);
    }
  }
}

Subdivision::~Subdivision() = default;
Subdivision::Subdivision(Subdivision&&) noexcept = default;
Subdivision& Subdivision::operator=(Subdivision&&) noexcept = default;

int Subdivision::depth() const { return impl_->depth; }
bool Subdivision::push_to_limit() const { return impl_->push_to_limit; }
const RefinedMesh& Subdivision::topology() const { return impl_->topology; }
int Subdivision::num_vertices() const { return static_cast<int>(impl_->out_vertices.size()); }
int Subdivision::num_colors() const { return static_cast<int>(impl_->out_colors.size()); }

// Refines N-channel data level by level, pushes the last level to the limit (when asked) and
// writes the output vertices (or color values) as floats.
template <int N, bool FaceVarying, class Gather>
void Subdivision::Impl::refine_and_limit(Gather gather, std::span<float> out, int stride, int offset) const {
  const auto count = [&](int level) {
    const Far::TopologyLevel& l = refiner->GetLevel(level);
    return FaceVarying ? l.GetNumFVarValues(0) : l.GetNumVertices();
  };
  std::vector<Value<N>> current(count(0)), next;
  const std::vector<int32_t>& base_map = FaceVarying ? sub.colors : sub.vertices;
  for (size_t i = 0; i < base_map.size(); ++i) gather(base_map[i], current[i].v);
  Far::PrimvarRefinerReal<double> primvar(*refiner);
  for (int level = 1; level <= depth; ++level) {
    next.resize(count(level));
    Value<N>* dst = next.data();
    if constexpr (FaceVarying) {
      primvar.InterpolateFaceVarying(level, current.data(), dst, 0);
    } else {
      primvar.Interpolate(level, current.data(), dst);
    }
    std::swap(current, next);
  }
  std::vector<Value<N>> limit;
  if (push_to_limit) {
    limit.resize(current.size());
    Value<N>* dst = limit.data();
    if constexpr (FaceVarying) {
      primvar.LimitFaceVarying(current.data(), dst, 0);
    } else {
      primvar.Limit(current.data(), dst);
    }
  } else {
    limit = std::move(current);
  }
  const std::vector<int32_t>& out_map = FaceVarying ? out_colors : out_vertices;
  if (out.size() < out_map.size() * stride) throw Error(ErrorCode::kInvalidArgument, "evaluate: output buffer too small");
  for (size_t i = 0; i < out_map.size(); ++i)
    for (int c = 0; c < N; ++c) out[i * stride + offset + c] = static_cast<float>(limit[out_map[i]].v[c]);
}

namespace {

// out (rows x N floats, row stride N) = s * values, rows split over threads; each row is summed in
// a fixed order, so the result does not depend on the thread count.
template <int N, class Get>
void apply_stencils(const SparseMatrix& s, Get get, std::span<float> out, int threads) {
  if (out.size() < size_t(s.rows()) * N) throw Error(ErrorCode::kInvalidArgument, "evaluate: output buffer too small");
  const int rows = static_cast<int>(s.rows());
  auto work = [&](int begin, int end) {
    for (int r = begin; r < end; ++r) {
      double acc[N] = {};
      for (SparseMatrix::InnerIterator it(s, r); it; ++it) {
        const auto v = get(static_cast<int>(it.col()));
        for (int c = 0; c < N; ++c) acc[c] += it.value() * v[c];
      }
      for (int c = 0; c < N; ++c) out[size_t(r) * N + c] = static_cast<float>(acc[c]);
    }
  };
  const int t = std::clamp(resolve_threads(threads), 1, std::max(1, rows / 4096));
  parallel_for(t, t, [&](int i) { work(int(int64_t(rows) * i / t), int(int64_t(rows) * (i + 1) / t)); });
}

}  // namespace

void Subdivision::Impl::refine_positions(std::span<const Vec2> positions, std::span<float> out) const {
  if (static_cast<int>(positions.size()) != num_control_vertices) {
    throw Error(ErrorCode::kInvalidArgument, "evaluate: position count does not match the mesh");
  }
  refine_and_limit<2, false>(
      [&](int i, double* v) {
        v[0] = positions[i].x;
        v[1] = positions[i].y;
      },
      out);
}

void Subdivision::Impl::refine_colors(std::span<const Color> colors, std::span<float> out, int threads) const {
  if (static_cast<int>(colors.size()) != num_control_colors) {
    throw Error(ErrorCode::kInvalidArgument, "evaluate: color count does not match the mesh");
  }
  if (resolve_threads(threads) > 1) {
    // Channels refine independently with the same weights in the same order, so splitting them
    // over threads gives bit-identical results: (r, g) as one job, b as the other.
    parallel_for(2, 2, [&](int job) {
      if (job == 0) {
        refine_and_limit<2, true>(
            [&](int i, double* v) {
              v[0] = colors[i].r;
              v[1] = colors[i].g;
            },
            out, 3, 0);
      } else {
        refine_and_limit<1, true>([&](int i, double* v) { v[0] = colors[i].b; }, out, 3, 2);
      }
    });
    return;
  }
  refine_and_limit<3, true>(
      [&](int i, double* v) {
        v[0] = colors[i].r;
        v[1] = colors[i].g;
        v[2] = colors[i].b;
      },
      out);
}

void Subdivision::evaluate_positions(std::span<const Vec2> positions, std::span<float> out, int threads) const {
  if (!impl_->use_stencils()) return impl_->refine_positions(positions, out);
  if (static_cast<int>(positions.size()) != impl_->num_control_vertices) {
    throw Error(ErrorCode::kInvalidArgument, "evaluate: position count does not match the mesh");
  }
  apply_stencils<2>(
      position_stencils(), [&](int i) { return std::array<double, 2>{positions[i].x, positions[i].y}; }, out,
      threads);
}

void Subdivision::evaluate_positions_once(std::span<const Vec2> positions, std::span<float> out) const {
  impl_->refine_positions(positions, out);
}

void Subdivision::evaluate_colors(std::span<const Color> colors, std::span<float> out, int threads) const {
  if (!impl_->use_stencils()) return impl_->refine_colors(colors, out, threads);
  if (static_cast<int>(colors.size()) != impl_->num_control_colors) {
    throw Error(ErrorCode::kInvalidArgument, "evaluate: color count does not match the mesh");
  }
  apply_stencils<3>(
      color_stencils(), [&](int i) { return std::array<double, 3>{colors[i].r, colors[i].g, colors[i].b}; }, out,
      threads);
}

void Subdivision::evaluate_with(std::span<const Vec2> positions, std::span<const Color> colors, RefinedMesh& out,
                                int threads, bool once) const {
  const RefinedMesh& topo = impl_->topology;
  if (out.triangles.size() != topo.triangles.size() || out.depth != topo.depth) {
    out = topo;
  }
  out.positions.resize(impl_->out_vertices.size() * 2);
  out.colors.resize(impl_->out_colors.size() * 3);
  auto evaluate_positions_here = [&] {
    if (once) {
      impl_->refine_positions(positions, out.positions);
    } else {
      evaluate_positions(positions, out.positions);
    }
  };
  auto evaluate_colors_here = [&] {
    if (once) {
      impl_->refine_colors(colors, out.colors, 1);
    } else {
      evaluate_colors(colors, out.colors, 1);
    }
  };
  // Positions and colors are independent passes over the same topology: run them side by side.
  parallel_for(2, threads, [&](int job) {
    if (job == 0) {
      evaluate_positions_here();
    } else {
      evaluate_colors_here();
    }
  });
}

void Subdivision::evaluate(std::span<const Vec2> positions, std::span<const Color> colors,
                           RefinedMesh& out, int threads) const {
  evaluate_with(positions, colors, out, threads, false);
}

void Subdivision::evaluate_once(std::span<const Vec2> positions, std::span<const Color> colors,
                                RefinedMesh& out, int threads) const {
  evaluate_with(positions, colors, out, threads, true);
}

namespace {

// Sparse rows over the control values, in CSR form.
struct StencilRows {
  std::vector<int32_t> offsets{0}, columns;
  std::vector<double> weights;
  int num_rows() const { return static_cast<int>(offsets.size()) - 1; }
};

// Masks recorded from PrimvarRefiner (destination value, source value, weight), grouped by
// destination in CSR form. PrimvarRefiner visits each destination once, but not in index order.
struct Masks {
  std::vector<int32_t> offsets, sources;
  std::vector<double> weights;
};
Masks group_masks(const std::vector<Eigen::Triplet<double, int32_t>>& triplets, int num_rows) {
  Masks m;
  m.offsets.assign(size_t(num_rows) + 1, 0);
  for (const auto& t : triplets) ++m.offsets[t.row() + 1];
  std::partial_sum(m.offsets.begin(), m.offsets.end(), m.offsets.begin());
  std::vector<int32_t> fill(m.offsets.begin(), m.offsets.end() - 1);
  m.sources.resize(triplets.size());
  m.weights.resize(triplets.size());
  for (const auto& t : triplets) {
    const int32_t k = fill[t.row()]++;
    m.sources[k] = t.col();
    m.weights[k] = t.value();
  }
  return m;
}

// out = masks x in, for the rows listed in `rows` (in that order), through a dense accumulator over
// the control values; exact zeros are dropped, and columns come out sorted when `sorted`.
StencilRows compose_rows(const Masks& masks, const StencilRows& in, std::span<const int32_t> rows, int num_control,
                         bool sorted) {
  StencilRows out;
  out.offsets.reserve(rows.size() + 1);
  out.columns.reserve(rows.size() * 12);
  out.weights.reserve(rows.size() * 12);
  std::vector<double> acc(num_control, 0.0);
  std::vector<uint8_t> seen(num_control, 0);
  std::vector<int32_t> touched(num_control + 1);
  for (const int32_t r : rows) {
    size_t num_touched = 0;
    for (int32_t e = masks.offsets[r]; e < masks.offsets[r + 1]; ++e) {
      const int32_t j = masks.sources[e];
      const double w = masks.weights[e];
      for (int32_t k = in.offsets[j]; k < in.offsets[j + 1]; ++k) {
        const int32_t c = in.columns[k];
        touched[num_touched] = c;  // kept only the first time c is seen
        num_touched += seen[c] ^ 1;
        seen[c] = 1;
        acc[c] += w * in.weights[k];
      }
    }
    if (sorted) std::sort(touched.begin(), touched.begin() + num_touched);
    for (size_t i = 0; i < num_touched; ++i) {
      const int32_t c = touched[i];
      if (acc[c] != 0.0) out.columns.push_back(c), out.weights.push_back(acc[c]);
      acc[c] = 0.0;
      seen[c] = 0;
    }
    out.offsets.push_back(static_cast<int32_t>(out.columns.size()));
  }
  return out;
}

// compose_rows() with large row sets split over all cores, as parts in row order; rows are
// independent, so the rows are the same for any split.
std::vector<StencilRows> compose_parts(const Masks& masks, const StencilRows& in, std::span<const int32_t> rows,
                                       int num_control, bool sorted) {
  const int parts = rows.size() < 65536 ? 1 : resolve_threads(0);
  std::vector<StencilRows> part(parts);
  parallel_for(parts, parts, [&](int i) {
    const size_t begin = rows.size() * i / parts, end = rows.size() * (i + 1) / parts;
    part[i] = compose_rows(masks, in, rows.subspan(begin, end - begin), num_control, sorted);
  });
  return part;
}

StencilRows compose(const Masks& masks, const StencilRows& in, std::span<const int32_t> rows, int num_control,
                    bool sorted) {
  std::vector<StencilRows> part = compose_parts(masks, in, rows, num_control, sorted);
  StencilRows out = std::move(part[0]);
  for (size_t i = 1; i < part.size(); ++i) {
    const int32_t base = static_cast<int32_t>(out.columns.size());
    for (size_t r = 1; r < part[i].offsets.size(); ++r) out.offsets.push_back(base + part[i].offsets[r]);
    out.columns.insert(out.columns.end(), part[i].columns.begin(), part[i].columns.end());
    out.weights.insert(out.weights.end(), part[i].weights.begin(), part[i].weights.end());
  }
  return out;
}

// The parts' rows, one after the other, as a compressed row-major matrix (written once, in place).
SparseMatrix to_matrix(const std::vector<StencilRows>& parts, int num_control) {
  int num_rows = 0;
  size_t nnz = 0;
  for (const StencilRows& p : parts) num_rows += p.num_rows(), nnz += p.columns.size();
  SparseMatrix m(num_rows, num_control);
  m.resizeNonZeros(static_cast<Eigen::Index>(nnz));
  int32_t* offsets = m.outerIndexPtr();
  int32_t* columns = m.innerIndexPtr();
  double* weights = m.valuePtr();
  int32_t row = 0, base = 0;
  for (const StencilRows& p : parts) {
    for (int r = 0; r < p.num_rows(); ++r) offsets[row++] = base + p.offsets[r];
    std::copy(p.columns.begin(), p.columns.end(), columns + base);
    std::copy(p.weights.begin(), p.weights.end(), weights + base);
    base += static_cast<int32_t>(p.columns.size());
  }
  offsets[row] = base;
  return m;
}

}  // namespace

// Limit stencils = (limit masks at the last level) x (refinement masks of each level) x ... x
// (the sub-mesh's values as control values), restricted to the output rows and expressed over the
// full control index space. The masks come from PrimvarRefiner applied to "unit" values that
// record their weights; composing them level by level keeps every row as short as its support.
SparseMatrix Subdivision::Impl::limit_stencils(bool face_varying) const {
  using Triplet = Eigen::Triplet<double, int32_t>;
  const std::vector<int32_t>& base_map = face_varying ? sub.colors : sub.vertices;
  const int num_control = face_varying ? num_control_colors : num_control_vertices;
  const auto count = [&](int level) {
    const Far::TopologyLevel& l = refiner->GetLevel(level);
    return face_varying ? l.GetNumFVarValues(0) : l.GetNumVertices();
  };

  // Level 0: each sub-mesh value is one control value.
  StencilRows rows;
  rows.offsets.resize(base_map.size() + 1);
  std::iota(rows.offsets.begin(), rows.offsets.end(), 0);
  rows.columns.assign(base_map.begin(), base_map.end());
  rows.weights.assign(base_map.size(), 1.0);

  Far::PrimvarRefinerReal<double> primvar(*refiner);
  std::vector<Triplet> triplets;
  std::vector<int32_t> all;
  UnitSource src;
  TripletSink sink{&triplets};
  for (int level = 1; level <= depth; ++level) {
    triplets.clear();
    triplets.reserve(size_t(count(level)) * 6);
    if (face_varying) {
      primvar.InterpolateFaceVarying(level, src, sink, 0);
    } else {
      primvar.Interpolate(level, src, sink);
    }
    all.resize(count(level));
    std::iota(all.begin(), all.end(), 0);
    rows = compose(group_masks(triplets, count(level)), rows, all, num_control, false);
  }

  // Limit masks at the last level (the identity without the limit push), for the output rows.
  const int num_last = count(depth);
  triplets.clear();
  if (push_to_limit) {
    triplets.reserve(size_t(num_last) * 8);
    if (face_varying) {
      primvar.LimitFaceVarying(src, sink, 0);
    } else {
      primvar.Limit(src, sink);
    }
  } else {
    for (int i = 0; i < num_last; ++i) triplets.emplace_back(i, i, 1.0);
  }
  const std::vector<int32_t>& out_map = face_varying ? out_colors : out_vertices;
  return to_matrix(compose_parts(group_masks(triplets, num_last), rows, out_map, num_control, true), num_control);
}

const SparseMatrix& Subdivision::position_stencils() const {
  if (!impl_->have_position_stencils) {
    impl_->position_stencils = impl_->limit_stencils(false);
    impl_->have_position_stencils = true;
  }
  return impl_->position_stencils;
}

const SparseMatrix& Subdivision::color_stencils() const {
  if (!impl_->have_color_stencils) {
    impl_->color_stencils = impl_->limit_stencils(true);
    impl_->have_color_stencils = true;
  }
  return impl_->color_stencils;
}

// ---------------------------------------------------------------------------------------------
// Exact limit evaluation: adaptive refinement isolates extraordinary vertices and sharp features,
// the patch table holds Loop box-spline patches (infinitely sharp ones for creases and tears) and
// Gregory triangles at irregular vertices; positions and colors are evaluated through the same
// basis, colors on the face-varying patches.

struct LimitEvaluator::Impl {
  std::unique_ptr<Far::TopologyRefiner> refiner;
  std::unique_ptr<const Far::PatchTable> patches;
  std::unique_ptr<Far::PatchMap> map;
  std::vector<Value2> points;  // refined vertices then local points
  std::vector<Value3> colors;  // refined fvar values then local points
  int num_faces = 0;
};

LimitEvaluator::LimitEvaluator(const ControlMesh& mesh, const MeshTopology& topo)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  SubMesh sub = make_submesh(mesh, topo, {});
  m.num_faces = mesh.num_triangles();
  m.refiner = make_refiner(mesh, topo, sub);

  Far::PatchTableFactory::Options options(6);
  options.SetEndCapType(Far::PatchTableFactory::Options::ENDCAP_GREGORY_BASIS);
  options.useInfSharpPatch = true;
  options.generateFVarTables = true;
  options.generateFVarLegacyLinearPatches = false;
  options.generateVaryingTables = false;
  options.SetPatchPrecision<double>();
  options.SetFVarPatchPrecision<double>();
  m.refiner->RefineAdaptive(options.GetRefineAdaptiveOptions());
  m.patches.reset(Far::PatchTableFactory::Create(*m.refiner, options));
  m.map = std::make_unique<Far::PatchMap>(*m.patches);

  // Values at every refined vertex, level by level, then the patches' local points.
  const int num_vertices = m.refiner->GetNumVerticesTotal();
  const int num_fvar = m.refiner->GetNumFVarValuesTotal(0);
  const int num_local = m.patches->GetNumLocalPoints();
  const int num_local_fvar = m.patches->GetNumLocalPointsFaceVarying(0);
  m.points.resize(size_t(num_vertices) + num_local);
  m.colors.resize(size_t(num_fvar) + num_local_fvar);
  for (int i = 0; i < mesh.num_vertices(); ++i) m.points[i].v[0] = mesh.positions[i].x, m.points[i].v[1] = mesh.positions[i].y;
  for (size_t i = 0; i < sub.colors.size(); ++i) {
    const Color& c = mesh.colors[sub.colors[i]];
    m.colors[i].v[0] = c.r;
    m.colors[i].v[1] = c.g;
    m.colors[i].v[2] = c.b;
  }
  Far::PrimvarRefinerReal<double> primvar(*m.refiner);
  Value2* p = m.points.data();
  Value3* c = m.colors.data();
  for (int level = 1; level <= m.refiner->GetMaxLevel(); ++level) {
    Value2* pdst = p + m.refiner->GetLevel(level - 1).GetNumVertices();
    Value3* cdst = c + m.refiner->GetLevel(level - 1).GetNumFVarValues(0);
    primvar.Interpolate(level, p, pdst);
    primvar.InterpolateFaceVarying(level, c, cdst, 0);
    p = pdst;
    c = cdst;
  }
  if (num_local > 0) {
    m.patches->GetLocalPointStencilTable<double>()->UpdateValues(m.points.data(), m.points.data() + num_vertices);
  }
  if (num_local_fvar > 0) {
    m.patches->GetLocalPointFaceVaryingStencilTable<double>(0)->UpdateValues(m.colors.data(),
                                                                             m.colors.data() + num_fvar);
  }
}

LimitEvaluator::~LimitEvaluator() = default;
LimitEvaluator::LimitEvaluator(LimitEvaluator&&) noexcept = default;
LimitEvaluator& LimitEvaluator::operator=(LimitEvaluator&&) noexcept = default;

LimitEvaluator::Sample LimitEvaluator::evaluate(int face, double u, double v) const {
  const Impl& m = *impl_;
  if (face < 0 || face >= m.num_faces) throw Error(ErrorCode::kInvalidArgument, "face " + std::to_string(face) + " out of range");
  const Far::PatchTable::PatchHandle* handle = m.map->FindPatch(face, u, v);
  if (!handle) throw Error(ErrorCode::kInvalidArgument, "no patch at the given face parameters");
  double w[20], wu[20], wv[20];
  Sample s;
  m.patches->EvaluateBasis(*handle, u, v, w, wu, wv);
  auto cvs = m.patches->GetPatchVertices(*handle);
  for (int i = 0; i < cvs.size(); ++i) {
    const Value2& q = m.points[cvs[i]];
    s.position.x += w[i] * q.v[0], s.position.y += w[i] * q.v[1];
    s.position_du.x += wu[i] * q.v[0], s.position_du.y += wu[i] * q.v[1];
    s.position_dv.x += wv[i] * q.v[0], s.position_dv.y += wv[i] * q.v[1];
  }
  m.patches->EvaluateBasisFaceVarying(*handle, u, v, w, wu, wv, nullptr, nullptr, nullptr, 0);
  auto fvs = m.patches->GetPatchFVarValues(*handle, 0);
  for (int i = 0; i < fvs.size(); ++i) {
    const Value3& q = m.colors[fvs[i]];
    for (int k = 0; k < 3; ++k) {
      s.color[k] += w[i] * q.v[k];
      s.color_du[k] += wu[i] * q.v[k];
      s.color_dv[k] += wv[i] * q.v[k];
    }
  }
  return s;
}

}  // namespace subvec
