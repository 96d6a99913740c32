// Tiny named control meshes for the subdivision tests. Every mesh is valid in the sense of
// mesh/validate.h: it tiles its image rectangle [0, width] x [0, height] with triangles of positive
// signed area (pixel coordinates, y down), its border vertices lie on the border, the four image
// corners are vertices, and color values are shared exactly across non-tear edges.
//
// Colors are assigned per "fan": the corners around a vertex that are not separated by a tear edge
// share one color value (assign_colors), so a tear vertex has one value per side and a tear
// endpoint inside the image has a single value shared by both sides.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "subvec/mesh/topology.h"
#include "subvec/mesh/vector_image.h"

namespace subvec::testing {

struct TestMesh {
  std::string name;
  ControlMesh mesh;
  int width = 0, height = 0;
  int focus = -1;  // the vertex the mesh is about (see each mesh), or -1

  MeshTopology topology() const { return MeshTopology::build(mesh, width, height); }
};

// (Re)assigns the color values of `m.mesh` from its features: one value per fan of corners, colored
// by `color(position of the vertex, one face of the fan)`.
void assign_colors(TestMesh& m, const std::function<Color(Vec2 position, int face)>& color);

// A smooth, non-linear color field used by the meshes below (values within 0-255).
Color smooth_color(Vec2 p);

// cols x rows grid cells of `spacing` pixels, each split by its (top-left, bottom-right)
// diagonal, so interior vertices have valence 6 (regular). With `jitter`, interior vertices move
// by up to 0.15 spacing (deterministic), so masks see generic data. Colors: smooth_color.
// focus: -1.
TestMesh grid_mesh(int cols, int rows, double spacing, bool jitter);

// A smooth interior vertex of valence n (3 <= n <= 12), focus, at the centre of a 16 x 16 image,
// with n spokes to a regular n-gon ring of radius 3; the ring is joined to the 12 border vertices
// (corners and thirds of the sides) by a strip merged by angle around the centre. The focus's
// vertex point stays at the centre (the ring is symmetric). Colors: smooth_color.
TestMesh valence_mesh(int n);

// A 20 x 20 image with a closed tear: a perturbed octagon of radius ~4.5 around the centre (feature
// id 1, focus = its first vertex). Inside, a fan from a centre vertex; outside, a ring of 12 smooth
// vertices at radius ~7.5, then the border (12 vertices). Colors: smooth_color inside, a different
// smooth field outside, so every tear vertex has two different color values. Vertex 0 is the
// centre and faces 0..7 (its fan) are exactly the inside.
TestMesh torn_disk();

// An 8 x 6 jittered grid (spacing 3) with an open tear along the middle row from grid vertex (2, 3)
// to (6, 3); both endpoints lie inside the image and have a single color value; focus = the
// endpoint (2, 3). Colors: smooth_color above the tear, a different field below.
TestMesh open_tear();

// An 8 x 8 jittered grid (spacing 3) with three tears leaving the junction vertex (4, 4), focus:
// to the left to (1, 4) and to the right to (7, 4) (ending inside the image), and down to the
// border vertex (4, 8). Three color regions meet at the junction (above; below left; below right).
TestMesh tear_junction();

// An 8 x 6 jittered grid (spacing 3) with an interior crease (no tear) from the border vertex
// (0, 3) along the middle row to (3, 3), then diagonally to (4, 4) and on to (5, 4), which ends
// inside the image (focus). Colors: smooth_color, one value per vertex.
TestMesh interior_crease();

// Every mesh above, with valence meshes for n = 3..8 and a 6 x 5 jittered grid.
std::vector<TestMesh> all_test_meshes();

}  // namespace subvec::testing
