// Vector exports of a vector image (docs/export.md): the limit surface (paper §3, as rendered in
// §7.1) as triangles, each control face refined only as deep as its own error needs (never deeper
// than `subvec render` refines at that scale) and stitched without cracks, then
//  - PDF: one ShadingType 4 (free-form Gouraud-shaded triangle mesh) shading, thin bands along the
//    tears that anti-alias them where a viewer does not anti-alias shadings, strokes as filled
//    paths;
//  - SVG: linear gradients over color cells of the faces (or flat triangles, where fewer bytes),
//    with crisp edges (no seams), and the same tear bands.
// Outputs are deterministic: the same image and options give the same bytes.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "subvec/mesh/vector_image.h"

namespace subvec {

// Which PDF viewers the shading is built for (docs/export.md, "PDF"). kAny: one Gouraud mesh with
// RGB vertex colors, which every viewer interpolates. kPoppler: three parameterized meshes, one per
// channel, blended with /BM /Lighten, which poppler's pdftoppm (Splash) interpolates per pixel, in
// two layers averaged by alpha (offset half an output unit, then a quarter apart; the second in
// reverse order), which give Splash's unsmoothed fill its pixel-centre sampling and a two-sample
// anti-aliasing of the tears; the offset shows as a half-unit shift of the mesh in viewers that
// sample at pixel centres (cairo, MuPDF, Ghostscript), and the file is about four times larger.
enum class PdfTarget { kAny, kPoppler };

// Which SVG renderers the file is built for (docs/export.md, "SVG"). kBrowser: linear gradients
// and flat triangles, drawn alike by browsers and librsvg. kInkscape: SVG 2 mesh gradients, one
// bicubic Coons patch per control face, which Inkscape draws and its mesh tool edits (browsers and
// librsvg draw nothing of them).
enum class SvgTarget { kBrowser, kInkscape };

struct ExportOptions {
  int level = 0;       // level of detail
  double scale = 1;    // output units (PDF points, SVG pixels) per image pixel
  int width = 0;       // > 0: the page's width in output units instead of `scale`
  // Each control face is refined until its triangles deviate from the limit surface by at most
  // `tolerance` output units in position where the surface has an edge (tears, the image border)
  // and `color_tolerance` levels (0-255 scale) in color elsewhere, where a misplaced point shows as
  // the color's slope times the distance; measured at the midpoints of the refined edges. Pieces
  // under one output unit are left as they are (at the surface's singular points, tear corners and
  // junctions, the error only halves per level).
  double tolerance = 0.25;
  double color_tolerance = 1.0;
  // SVG for browsers (docs/export.md, "SVG"): each face is drawn either as color cells, each one
  // linear gradient whose mean difference from the limit surface's color at its corners and edge
  // midpoints is at most `linear_color_tolerance` levels, or as flat triangles, each within
  // `flat_color_tolerance` levels of the limit there (the largest difference), whichever takes
  // fewer bytes.
  double linear_color_tolerance = 8.0;
  double flat_color_tolerance = 3.0;
  int depth = -1;      // 0..8: this subdivision depth instead of the tolerance rule
  int max_depth = 6;   // the tolerance rule stops here, or at the renderer's depth if lower
  // PDF: along both sides of every tear, a band one output unit wide in that side's color, so that
  // viewers that do not anti-alias shadings (poppler) still show anti-aliased tears.
  bool tear_hints = true;
  PdfTarget pdf_target = PdfTarget::kAny;
  SvgTarget svg_target = SvgTarget::kBrowser;
};

struct ExportReport {
  int depth = 0;      // the deepest control face's depth
  int min_depth = 0;  // the shallowest's
  int64_t triangles = 0;
  // Measured at `depth` by the tolerance rule (zero with an explicit depth): the largest
  // deviations (output units, levels) and the fraction of refined edges over a tolerance.
  double max_position_error = 0;
  double max_color_error = 0;
  double over_tolerance = 0;
  // What the file holds: mesh patches (SvgTarget::kInkscape, else 0), tear-hint paths, stroke
  // outlines, and its size.
  int64_t patches = 0;
  // SvgTarget::kBrowser: the shapes that fill the mesh (a color cell's outline, or a flat
  // triangle), and how many of them are linear gradients.
  int64_t shapes = 0;
  int64_t gradients = 0;
  int64_t tear_hints = 0;
  int64_t strokes = 0;
  int64_t objects = 0;  // objects drawn (the visible ones of the level), each as its own group
  int64_t bytes = 0;
};

// Output units per image pixel: width / image_width when `width` is given, else `scale`.
double export_scale(const ExportOptions& options, int image_width);

// Throws Error(kInvalidArgument) for a bad level, scale, tolerance or depth, Error(kInvalidMesh)
// when the level fails validation.
std::string to_pdf(const VectorImage& image, const ExportOptions& options = {},
                   ExportReport* report = nullptr);
std::string to_svg(const VectorImage& image, const ExportOptions& options = {},
                   ExportReport* report = nullptr);

// By extension (.pdf, .svg, case-insensitive), written atomically.
bool is_vector_export(const std::filesystem::path& path);
void write_vector_export(const std::filesystem::path& path, const VectorImage& image,
                         const ExportOptions& options = {}, ExportReport* report = nullptr);

}  // namespace subvec
