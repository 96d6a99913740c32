// PDF export (export.h, docs/export.md): one page of W x H image pixels times the scale, in points;
// the limit mesh as a ShadingType 4 shading (PDF 32000-1:2008, 8.7.4.5.5) painted with `sh`, then
// tear hints (export_p.h) and strokes as filled paths. The shading's vertices are packed as 8-bit
// flags, 24-bit coordinates (Decode maps them onto [0, W] x [0, H] image pixels) and 16-bit color
// components, in strips (flags 1 and 2 reuse the previous triangle's vertices), Flate-compressed.
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <span>
#include <string>
#include <vector>

#include "export/export_p.h"
#include "export/limit_mesh_p.h"
#include "subvec/core/error.h"
#include "subvec/export/export.h"

namespace subvec {
namespace {

// zlib-compressed bytes, as the text of a PDF stream.
template <class Bytes>
std::string deflate(const Bytes& data) {
  uLongf size = compressBound(static_cast<uLong>(data.size()));
  std::string out(size, '\0');
  const auto* in = reinterpret_cast<const Bytef*>(data.data());
  if (compress2(reinterpret_cast<Bytef*>(out.data()), &size, in, static_cast<uLong>(data.size()), 9) !=
      Z_OK)
    throw Error(ErrorCode::kIo, "zlib compression failed");
  out.resize(size);
  return out;
}

// A PDF text string: printable ASCII as a literal (parentheses and backslashes escaped), anything
// else as UTF-16BE with a byte order mark, in hex (invalid UTF-8 becomes U+FFFD).
std::string pdf_string(const std::string& s) {
  if (std::all_of(s.begin(), s.end(), [](char c) { return c >= 0x20 && c <= 0x7E; })) {
    std::string out = "(";
    for (const char c : s) {
      if (c == '(' || c == ')' || c == '\\') out += '\\';
      out += c;
    }
    return out + ")";
  }
  std::string out = "<FEFF";
  auto unit = [&](uint32_t u) {
    char buf[8];
    std::snprintf(buf, sizeof buf, "%04X", u);
    out += buf;
  };
  for (size_t i = 0; i < s.size();) {
    const auto b = static_cast<unsigned char>(s[i]);
    const int n = b < 0x80 ? 1 : (b >> 5) == 6 ? 2 : (b >> 4) == 14 ? 3 : (b >> 3) == 30 ? 4 : 0;
    uint32_t cp = n == 1 ? b : n == 2 ? b & 0x1F : n == 3 ? b & 0x0F : b & 0x07;
    bool ok = n > 0 && i + n <= s.size();
    for (int k = 1; ok && k < n; ++k) {
      const auto c = static_cast<unsigned char>(s[i + k]);
      ok = (c >> 6) == 2;
      cp = (cp << 6) | (c & 0x3F);
    }
    if (!ok || cp > 0x10FFFF || (cp >= 0xD800 && cp < 0xE000)) cp = 0xFFFD;
    i += ok ? n : 1;
    if (cp >= 0x10000) {
      unit(0xD800 + ((cp - 0x10000) >> 10));
      unit(0xDC00 + ((cp - 0x10000) & 0x3FF));
    } else {
      unit(cp);
    }
  }
  return out + ">";
}

// The same strips, last first (each strip as it was).
detail::Strips reversed(const detail::Strips& strips) {
  std::vector<size_t> starts;  // a strip: three corners with flag 0, then one per triangle more
  for (size_t i = 0; i < strips.flags.size(); ++i) {
    if (strips.flags[i] == 0) {
      starts.push_back(i);
      i += 2;
    }
  }
  detail::Strips out;
  out.corners.reserve(strips.corners.size());
  out.flags.reserve(strips.flags.size());
  for (size_t k = starts.size(); k-- > 0;) {
    const size_t end = k + 1 < starts.size() ? starts[k + 1] : strips.flags.size();
    const auto from = static_cast<std::ptrdiff_t>(starts[k]), to = static_cast<std::ptrdiff_t>(end);
    const auto& c = strips.corners;
    out.corners.insert(out.corners.end(), c.begin() + from, c.begin() + to);
    out.flags.insert(out.flags.end(), strips.flags.begin() + from, strips.flags.begin() + to);
  }
  return out;
}

// A stream object's body: the dictionary `dict` (open) closed with the data's length, and the data.
std::string stream_object(std::string dict, const std::string& data) {
  return dict + " /Length " + std::to_string(data.size()) + " >>\nstream\n" + data + "\nendstream";
}

// Consecutive tear bands whose colors are this close (levels) are drawn as one (export_p.h).
constexpr double kHintColorTolerance = 1.0;

// The tear hints and strokes drawn over the shadings, in image pixels.
std::string hints(const RefinedMesh& mesh, const ExportOptions& options, double s, ExportReport& report) {
  std::string content;
  if (options.tear_hints) {
    // Coordinates to a hundredth of an output unit, colors to a quarter of a level.
    const int decimals = std::clamp(static_cast<int>(std::ceil(std::log10(s * 100) - 1e-9)), 1, 9);
    for (const detail::TearHint& hint : detail::tear_hints(mesh, 1.0 / s, kHintColorTolerance)) {
      ++report.tear_hints;
      for (const double c : hint.color)
        content += detail::fixed(std::clamp(c / 255.0, 0.0, 1.0), 3) + " ";
      content += "rg";
      for (size_t k = 0; k < hint.polygon.size(); ++k) {
        content += " " + detail::fixed(hint.polygon[k].x, decimals) + " " +
                   detail::fixed(hint.polygon[k].y, decimals) + (k == 0 ? " m" : " l");
      }
      content += " h f\n";
    }
  }
  return content;
}

// The strokes of options.level (the image's, or an object's) as filled outlines.
std::string strokes(std::span<const Stroke> list, const ExportOptions& options, ExportReport& report) {
  std::string content;
  for (const Stroke& stroke : list) {
    if (stroke.level != options.level) continue;
    const std::vector<Vec2> outline = detail::stroke_outline(stroke);
    if (outline.empty()) continue;
    ++report.strokes;
    const float rgb[3] = {stroke.color.r, stroke.color.g, stroke.color.b};
    for (const float c : rgb) content += detail::fixed(std::clamp(c / 255.0, 0.0, 1.0), 4) + " ";
    content += "rg\n";
    for (size_t i = 0; i < outline.size(); ++i) {
      content += detail::fixed(outline[i].x, 3) + " " + detail::fixed(outline[i].y, 3) +
                 (i == 0 ? " m\n" : " l\n");
    }
    content += "h f\n";
  }
  return content;
}

// The file: objects 1 to 5 (catalog, pages, page, contents, info), then `extra`, and the xref.
std::string assemble(const VectorImage& image, double w, double h, double s, const std::string& resources,
                     const std::string& content, const std::vector<std::string>& extra) {
  std::string pdf = "%PDF-1.4\n%\xE2\xE3\xCF\xD3\n";
  std::vector<size_t> offsets;
  auto object = [&](const std::string& body) {
    offsets.push_back(pdf.size());
    pdf += std::to_string(offsets.size()) + " 0 obj\n" + body + "\nendobj\n";
  };
  std::string title;
  for (const auto& [key, value] : image.metadata)
    if (key == "title") title = value;
  object("<< /Type /Catalog /Pages 2 0 R >>");
  object("<< /Type /Pages /Kids [3 0 R] /Count 1 >>");
  object("<< /Type /Page /Parent 2 0 R /MediaBox [0 0 " + detail::fixed(w * s, 6) + " " +
         detail::fixed(h * s, 6) + "] /Contents 4 0 R /Resources << " + resources + " >> >>");
  object(stream_object("<< /Filter /FlateDecode", deflate(content)));
  object("<< /Producer (subvec)" + (title.empty() ? "" : " /Title " + pdf_string(title)) + " >>");
  for (const std::string& body : extra) object(body);
  const size_t xref = pdf.size();
  pdf += "xref\n0 " + std::to_string(offsets.size() + 1) + "\n0000000000 65535 f \n";
  for (const size_t o : offsets) {
    char line[24];
    std::snprintf(line, sizeof line, "%010zu 00000 n \n", o);
    pdf += line;
  }
  pdf += "trailer\n<< /Size " + std::to_string(offsets.size() + 1) +
         " /Root 1 0 R /Info 5 0 R >>\nstartxref\n" + std::to_string(xref) + "\n%%EOF\n";
  return pdf;
}

}  // namespace

std::string to_pdf(const VectorImage& image, const ExportOptions& options, ExportReport* report) {
  ExportReport local;
  ExportReport& r = report ? *report : local;
  const RefinedMesh mesh =
      detail::export_mesh(image, options, detail::Shading::kGouraud, r);
  const std::vector<detail::ObjectMesh> objects =
      detail::export_object_meshes(image, options, detail::Shading::kGouraud, r);
  const double w = image.width, h = image.height, s = export_scale(options, image.width);

  // The shading streams.
  // PdfTarget::kAny: one shading with RGB at the vertices. kPoppler: parameterized shadings per
  // channel (t = that channel's value, a linear Function onto red, green or blue), which poppler's
  // Splash interpolates per pixel where it fills an RGB mesh in flat pieces, combined over black
  // with /BM /Lighten (the maximum of (r,0,0), (0,g,0), (0,0,b) is (r,g,b)), in two layers (below).
  const bool channels = options.pdf_target == PdfTarget::kPoppler;
  const detail::Strips strips = detail::make_strips(mesh);
  // Coordinates in 16 bits where their step is within an eighth of the position tolerance (pages
  // up to about 1000 units at the default), else 24; colors in 8 bits, which measured the same in
  // every viewer as 16 (docs/export.md); the poppler target's channel parameters in 16, since
  // Splash interpolates them per pixel.
  const int cbits = std::max(w, h) * s / 65535 <= options.tolerance / 8 ? 16 : 24;
  const int kbits = channels ? 16 : 8;
  const double kCoordinateMax = double((1 << cbits) - 1);
  // The coordinates reach two output units past the page's right edge, where one triangle of no
  // area ends the mesh: PDF.js draws a mesh into an image as wide as the mesh and writes one pixel
  // past the end of each row, so the mesh's last column would land in the next row's first, on
  // the page (docs/export.md, "PDF.js").
  // The right edge x = w is a whole code, so that it decodes to w (MuPDF rounds vertices to
  // pixels, and a right edge a hair inside the page lost it the last column).
  // The coordinates' range: [x0, x_end] x [y0, y1] in image pixels, the page for the level's mesh
  // and an object's bounding box for its own.
  struct Range {
    double x0 = 0, x_end = 0, y0 = 0, y1 = 0;
  };
  auto range_of = [&](double x0, double x1, double y0, double y1) {
    const double span = x1 - x0;
    return Range{x0, x0 + span * kCoordinateMax / std::floor(kCoordinateMax * span / (span + 2 / s)), y0, y1};
  };
  const Range page = range_of(0, w, 0, h);
  auto stream = [&](const RefinedMesh& drawn, const Range& range, const detail::Strips& part, int channel) {
    std::vector<uint8_t> data;
    data.reserve(part.flags.size() * (channel < 0 ? 13 : 9));
    auto put = [&](uint64_t v, int bytes) {
      for (int k = bytes - 1; k >= 0; --k) data.push_back(static_cast<uint8_t>(v >> (8 * k)));
    };
    for (size_t i = 0; i < part.flags.size(); ++i) {
      const auto [t, k] = part.corners[i];
      const int32_t v = drawn.triangles[t][k], c = drawn.triangle_colors[t][k];
      put(part.flags[i], 1);
      const double x = (drawn.positions[2 * v] - range.x0) / (range.x_end - range.x0);
      const double y = (drawn.positions[2 * v + 1] - range.y0) / (range.y1 - range.y0);
      put(uint64_t(std::lround(std::clamp(x, 0.0, 1.0) * kCoordinateMax)), cbits / 8);
      put(uint64_t(std::lround(std::clamp(y, 0.0, 1.0) * kCoordinateMax)), cbits / 8);
      for (int ch = 0; ch < 3; ++ch) {
        if (channel >= 0 && ch != channel) continue;
        const double value = std::clamp(double(drawn.colors[3 * c + ch]) / 255.0, 0.0, 1.0);
        put(uint64_t(std::lround(value * double((1 << kbits) - 1))), kbits / 8);
      }
    }
    for (int corner = 0; corner < 3; ++corner) {  // the triangle of no area at (x_end, 0)
      put(0, 1);
      put(uint64_t(kCoordinateMax), cbits / 8);
      put(0, cbits / 8);
      put(0, (channel < 0 ? 3 : 1) * kbits / 8);
    }
    return deflate(data);
  };

  // Objects 1 to 5 are fixed (catalog, pages, page, contents, info); shadings and forms follow.
  std::vector<std::string> extra;  // bodies of objects 6, 7, ...
  auto add = [&](std::string body) {
    extra.push_back(std::move(body));
    return std::to_string(5 + extra.size()) + " 0 R";
  };
  auto shading = [&](const std::string& data, int channel, double offset, const Range& range) {
    const std::string decode = "/Decode [" + detail::fixed(range.x0, 6) + " " + detail::fixed(range.x_end, 6) +
                               " " + detail::fixed(range.y0, 6) + " " + detail::fixed(range.y1, 6);
    std::string dict = "<< /ShadingType 4 /ColorSpace /DeviceRGB /BitsPerCoordinate " + std::to_string(cbits) +
                       " /BitsPerComponent " + std::to_string(kbits) + " /BitsPerFlag 8 " + decode;

    if (channel < 0) {
      dict += " 0 1 0 1 0 1]";
    } else {
      // t -> (t + offset) on the channel, clipped to [0, 1] by the Range.
      std::string c0 = "[", c1 = "[";
      for (int k = 0; k < 3; ++k) {
        c0 += std::string(k ? " " : "") + (k == channel ? detail::fixed(offset, 6) : "0");
        c1 += std::string(k ? " " : "") + (k == channel ? detail::fixed(1 + offset, 6) : "0");
      }
      dict += " 0 1] /Function << /FunctionType 2 /Domain [0 1] /Range [0 1 0 1 0 1] /C0 " + c0 +
              "] /C1 " + c1 + "] /N 1 >>";
    }
    return add(stream_object(dict + " /Filter /FlateDecode", data));
  };

  // The page: image pixels to points, y up.
  std::string content = "q " + detail::fixed(s, 6) + " 0 0 " + detail::fixed(-s, 6) + " 0 " +
                        detail::fixed(h * s, 6) + " cm\n";
  std::string resources;
  if (!channels) {
    resources = "/Shading << /Sh0 " + shading(stream(mesh, page, strips, -1), -1, 0, page) + " >>";
    content += "/Sh0 sh\n";
  } else {
    // Two layers, each the three channel meshes over black in an isolated transparency group (a
    // form XObject), painted with alpha 1 and then 1/2: the page shows their mean. What poppler's
    // Splash does with a parameterized mesh (docs/export.md): it rounds the vertices to whole
    // device pixels, colors pixel (X, Y) with the value at that corner, not at the pixel's centre,
    // and fills each triangle's boundary pixels too, so that where two triangles meet the later
    // one wins, whole pixels, and at a tear the side drawn last takes the pixels on it. So:
    // - both layers are shifted half an output unit up and left (centre sampling), then a quarter
    //   unit apart along a diagonal, so their roundings differ and average;
    // - the second layer draws the strips in the reverse order, so that each side of a tear takes
    //   the pixels on it in one layer of the two (a two-sample anti-aliasing of the tears, under
    //   the tear hints drawn after);
    // - Splash's 50 % blend floors the mean of the two layers, so the second layer's colors are
    //   rounded up (half a level added) instead of to the nearest: where the layers agree the page
    //   gets the exact rounded value, floor((round(x) + ceil(x)) / 2) = round(x).
    const detail::Strips backward = reversed(strips);
    auto at = [&](double x, double y) {  // a translation by (x, y) output units
      return detail::fixed(x / s, 6) + " " + detail::fixed(y / s, 6);
    };
    std::string forms;
    for (int layer = 0; layer < 2; ++layer) {
      std::string names, paint = "0 0 0 rg -1 -1 " + detail::fixed(w + 2, 6) + " " +
                                 detail::fixed(h + 2, 6) + " re f /GS0 gs";
      for (int ch = 0; ch < 3; ++ch) {
        const std::string name = "/Sh" + std::to_string(ch);
        const double offset = layer == 0 ? 0 : 0.5 / 255;
        names += " " + name + " " + shading(stream(mesh, page, layer == 0 ? strips : backward, ch), ch, offset, page);
        paint += " " + name + " sh";
      }
      const std::string group =
          "<< /Type /XObject /Subtype /Form /BBox [-1 -1 " + detail::fixed(w + 1, 6) + " " +
          detail::fixed(h + 1, 6) + "] /Group << /S /Transparency /I true /CS /DeviceRGB >>" +
          " /Resources << /Shading <<" + names + " >> /ExtGState << /GS0 << /BM /Lighten >> >> >>";
      forms += " /Fm" + std::to_string(layer) + " " + add(stream_object(group, paint));
      content += "q /GA" + std::to_string(layer) + " gs 1 0 0 1 " +
                 (layer == 0 ? at(-0.75, -0.25) : at(-0.25, -0.75)) + " cm /Fm" +
                 std::to_string(layer) + " Do Q\n";
    }
    resources = "/XObject <<" + forms + " >> /ExtGState << /GA0 << /ca 1 >> /GA1 << /ca 0.5 >> >>";
  }
  content += hints(mesh, options, s, r);
  // Each object over the level, bottom to top: its own RGB mesh (whatever the target), in a marked
  // group named by the object, with the hints along its tears.
  std::string object_shadings;
  for (const detail::ObjectMesh& object : objects) {
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (int i = 0; i < object.mesh.num_vertices(); ++i) {
      x0 = std::min(x0, double(object.mesh.positions[2 * i])), x1 = std::max(x1, double(object.mesh.positions[2 * i]));
      y0 = std::min(y0, double(object.mesh.positions[2 * i + 1])), y1 = std::max(y1, double(object.mesh.positions[2 * i + 1]));
    }
    // The mesh's own box, clipped to it: the triangle of no area that ends the mesh (for PDF.js,
    // above) lies past its right side, and inside the page it would show as a dot.
    const double bx0 = std::floor(x0), bx1 = std::ceil(x1) + 1, by0 = std::floor(y0), by1 = std::ceil(y1) + 1;
    const Range range = range_of(bx0, bx1, by0, by1);
    const std::string clip = detail::fixed(bx0, 6) + " " + detail::fixed(by0, 6) + " " +
                             detail::fixed(bx1 - bx0, 6) + " " + detail::fixed(by1 - by0, 6) + " re W n ";
    const std::string name = "/Ob" + std::to_string(object.object);
    object_shadings += " " + name + " " +
                       shading(stream(object.mesh, range, detail::make_strips(object.mesh), -1), -1, 0, range);
    content += "/Subvec_object_" + std::to_string(object.object) + " BMC q q " + clip + name + " sh Q\n" +
               hints(object.mesh, options, s, r) + strokes(image.objects[object.object].strokes, options, r) +
               "Q EMC\n";
  }
  if (!object_shadings.empty()) {
    if (!channels) {
      resources.insert(resources.size() - 3, object_shadings);  // before the dictionary's " >>"
    } else {
      resources += " /Shading <<" + object_shadings + " >>";
    }
  }
  content += strokes(image.strokes, options, r);
  content += "Q\n";

  std::string pdf = assemble(image, w, h, s, resources, content, extra);
  r.bytes = static_cast<int64_t>(pdf.size());
  return pdf;
}

}  // namespace subvec
