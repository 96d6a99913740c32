// Helpers shared by the file format tests: small valid images, a raw zstd frame builder, the
// worked examples of docs/format.md, and error expectations.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

#include "subvec/core/error.h"
#include "subvec/mesh/vector_image.h"

namespace subvec::svec_test {

inline std::filesystem::path source_dir() { return SUBVEC_SOURCE_DIR; }

inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  EXPECT_TRUE(in.good()) << path;
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// The 4 x 4 image of docs/format.md: corners 0-3, center 4, four triangles, color i on vertex i.
inline VectorImage square_image() {
  VectorImage image;
  image.width = 4;
  image.height = 4;
  ControlMesh m;
  m.positions = {{0, 0}, {4, 0}, {4, 4}, {0, 4}, {2, 2}};
  m.colors = {{255, 0, 0}, {255, 0, 0}, {0, 0, 255}, {0, 0, 255}, {127.5f, 0, 127.5f}};
  m.triangles = {{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
  m.triangle_colors = m.triangles;
  image.levels.push_back(m);
  return image;
}

// An image exercising every field: two levels (a jittered grid with an open tear and an interior
// crease; the 4 x 4 square scaled up), awkward numbers, strokes and metadata that needs escaping.
inline VectorImage rich_image() {
  VectorImage image;
  image.width = 60;
  image.height = 40;
  const int nx = 6, ny = 4, tear_row = 2, tear_end = 3, crease_col = 4;
  ControlMesh m;
  auto id = [&](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      double x = 10.0 * i, y = 10.0 * j;
      const bool border_x = i == 0 || i == nx, border_y = j == 0 || j == ny;
      if (!border_x) x += 0.3 * std::sin(1.7 * i + 2.3 * j) + 1.0 / 3.0;
      if (!border_y) y += 0.3 * std::cos(2.9 * i + 0.7 * j) - 1e-7;
      m.positions.push_back({x, y});
    }
  }
  // One color per vertex, plus a second one below the tear for the tear vertices left of its end.
  for (int v = 0; v < (nx + 1) * (ny + 1); ++v) {
    m.colors.push_back({float(v) * 3.1f + 0.1f, 255.0f - float(v) * 1.37f, 1e-3f * float(v * v)});
  }
  std::vector<int32_t> below(nx + 1, -1);
  for (int i = 0; i < tear_end; ++i) {
    below[i] = m.num_colors();
    m.colors.push_back({17.25f + float(i), 0.1f, 200.0f / 3.0f});
  }
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const Tri t1 = {id(i, j), id(i + 1, j), id(i + 1, j + 1)};
      const Tri t2 = {id(i, j), id(i + 1, j + 1), id(i, j + 1)};
      for (const Tri& t : {t1, t2}) {
        Tri c = t;
        for (int k = 0; k < 3; ++k) {
          const int vi = t[k] % (nx + 1), vj = t[k] / (nx + 1);
          if (j >= tear_row && vj == tear_row && below[vi] >= 0) c[k] = below[vi];
        }
        m.triangles.push_back(t);
        m.triangle_colors.push_back(c);
      }
    }
  }
  Feature tear;
  tear.id = 7;
  tear.saliency = 0.625;
  for (int i = 0; i <= tear_end; ++i) tear.vertices.push_back(id(i, tear_row));
  m.features.push_back(tear);
  m.creases = {{id(crease_col, 1), id(crease_col, 2)}, {id(crease_col, 3), id(crease_col, 2)}};
  image.levels.push_back(m);

  ControlMesh coarse = square_image().levels[0];
  for (Vec2& p : coarse.positions) p = {p.x * 15, p.y * 10};
  image.levels.push_back(coarse);

  Stroke s;
  s.level = 1;
  s.points = {{1.5, 2.25}, {30, 20.125}, {59.9, 0.1}};
  s.width = 2.5f;
  s.color = {10, 20.5f, 30.25f};
  s.taper = 0.1f;
  image.strokes.push_back(s);
  Stroke t;
  t.points = {{0, 0}, {60, 40}};
  image.strokes.push_back(t);
  image.metadata = {{"title", "rich \"test\" image"},
                    {"note", "line one\nline two\ttab \\ backslash"},
                    {"unicode", "caf\xc3\xa9 \xe2\x9c\x93"}};
  return image;
}

// The fenced blocks tagged `json svec-example` in docs/format.md, verbatim.
inline std::vector<std::string> doc_examples() {
  const std::string doc = read_text(source_dir() / "docs" / "format.md");
  std::vector<std::string> blocks;
  const std::string open = "```json svec-example\n";
  for (size_t pos = doc.find(open); pos != std::string::npos; pos = doc.find(open, pos)) {
    pos += open.size();
    const size_t end = doc.find("```", pos);
    if (end == std::string::npos) break;
    blocks.push_back(doc.substr(pos, end - pos));
    pos = end;
  }
  return blocks;
}

// A zstd frame (RFC 8878) holding `data` in raw (stored) blocks, with the content size in the
// frame header and no checksum: lets tests craft payloads byte by byte.
inline std::vector<uint8_t> raw_zstd_frame(const std::vector<uint8_t>& data) {
  std::vector<uint8_t> out = {0x28, 0xB5, 0x2F, 0xFD};
  out.push_back(0xE0);  // frame header descriptor: 8-byte content size, single segment
  for (int k = 0; k < 8; ++k) out.push_back(static_cast<uint8_t>(uint64_t(data.size()) >> (8 * k)));
  size_t pos = 0;
  do {
    const size_t n = std::min<size_t>(data.size() - pos, 1 << 17);
    const bool last = pos + n == data.size();
    const uint32_t header = (uint32_t(n) << 3) | (last ? 1u : 0u);  // block type 0: raw
    for (int k = 0; k < 3; ++k) out.push_back(static_cast<uint8_t>(header >> (8 * k)));
    out.insert(out.end(), data.begin() + long(pos), data.begin() + long(pos + n));
    pos += n;
  } while (pos < data.size());
  return out;
}

// Little-endian byte builder for crafted payloads and headers.
struct Bytes {
  std::vector<uint8_t> b;
  Bytes& u32(uint32_t v) {
    for (int k = 0; k < 4; ++k) b.push_back(static_cast<uint8_t>(v >> (8 * k)));
    return *this;
  }
  Bytes& u64(uint64_t v) {
    for (int k = 0; k < 8; ++k) b.push_back(static_cast<uint8_t>(v >> (8 * k)));
    return *this;
  }
  Bytes& i32(int32_t v) { return u32(static_cast<uint32_t>(v)); }
  Bytes& f32(float v) { return u32(std::bit_cast<uint32_t>(v)); }
  Bytes& f64(double v) { return u64(std::bit_cast<uint64_t>(v)); }
  Bytes& raw(const std::vector<uint8_t>& v) {
    b.insert(b.end(), v.begin(), v.end());
    return *this;
  }
};

// A whole .svec file around a payload: magic, version, flags, sizes, raw zstd frame.
inline std::vector<uint8_t> svec_file(const std::vector<uint8_t>& payload, uint32_t version = 1,
                                      uint32_t flags = 0) {
  const std::vector<uint8_t> frame = raw_zstd_frame(payload);
  Bytes file;
  file.raw({'S', 'U', 'B', 'V', 'E', 'C', 0x00, 0x1A}).u32(version).u32(flags);
  file.u64(payload.size()).u64(frame.size()).raw(frame);
  return file.b;
}

// Payload of square_image(), field by field, as docs/format.md lays it out.
inline Bytes square_payload() {
  Bytes p;
  p.i32(4).i32(4).u32(1);
  p.u32(5).u32(5).u32(4).u32(0).u32(0);
  const double xy[5][2] = {{0, 0}, {4, 0}, {4, 4}, {0, 4}, {2, 2}};
  for (auto& v : xy) p.f64(v[0]).f64(v[1]);
  const float rgb[5][3] = {{255, 0, 0}, {255, 0, 0}, {0, 0, 255}, {0, 0, 255}, {127.5f, 0, 127.5f}};
  for (auto& c : rgb) p.f32(c[0]).f32(c[1]).f32(c[2]);
  const int32_t tris[4][3] = {{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
  for (int pass = 0; pass < 2; ++pass)
    for (auto& t : tris) p.i32(t[0]).i32(t[1]).i32(t[2]);
  p.u32(0).u32(0);  // strokes, metadata
  return p;
}

// Field-by-field exact equality of two images (floats compared with ==).
inline void expect_same(const VectorImage& a, const VectorImage& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  ASSERT_EQ(a.levels.size(), b.levels.size());
  for (size_t l = 0; l < a.levels.size(); ++l) {
    SCOPED_TRACE("level " + std::to_string(l));
    const ControlMesh &x = a.levels[l], &y = b.levels[l];
    EXPECT_EQ(x.positions, y.positions);
    EXPECT_EQ(x.colors, y.colors);
    EXPECT_EQ(x.triangles, y.triangles);
    EXPECT_EQ(x.triangle_colors, y.triangle_colors);
    EXPECT_EQ(x.creases, y.creases);
    ASSERT_EQ(x.features.size(), y.features.size());
    for (size_t i = 0; i < x.features.size(); ++i) {
      EXPECT_EQ(x.features[i].id, y.features[i].id);
      EXPECT_EQ(x.features[i].vertices, y.features[i].vertices);
      EXPECT_EQ(x.features[i].saliency, y.features[i].saliency);
    }
  }
  ASSERT_EQ(a.strokes.size(), b.strokes.size());
  for (size_t i = 0; i < a.strokes.size(); ++i) {
    EXPECT_EQ(a.strokes[i].level, b.strokes[i].level);
    EXPECT_EQ(a.strokes[i].points, b.strokes[i].points);
    EXPECT_EQ(a.strokes[i].width, b.strokes[i].width);
    EXPECT_EQ(a.strokes[i].color, b.strokes[i].color);
    EXPECT_EQ(a.strokes[i].taper, b.strokes[i].taper);
  }
  EXPECT_EQ(a.metadata, b.metadata);
}

// Runs `f`, which must throw subvec::Error with `code` and a message containing every one of
// `parts`; the message must be a single line.
inline void expect_error(const std::function<void()>& f, ErrorCode code,
                         const std::vector<std::string>& parts) {
  try {
    f();
    ADD_FAILURE() << "no error thrown; expected one containing \"" << parts.front() << "\"";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_EQ(static_cast<int>(e.code()), static_cast<int>(code)) << message;
    for (const std::string& part : parts) {
      EXPECT_NE(message.find(part), std::string::npos)
          << "message \"" << message << "\" lacks \"" << part << "\"";
    }
    EXPECT_EQ(message.find('\n'), std::string::npos) << "multi-line message: " << message;
  }
}

}  // namespace subvec::svec_test
