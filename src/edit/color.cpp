// Color editing (edit/color.h).
#include "subvec/edit/color.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "core/messages_p.h"
#include "subvec/core/error.h"

namespace subvec {
namespace {

using detail::invalid;
using detail::num;

std::string color_name(Color c) { return "[" + num(c.r) + ", " + num(c.g) + ", " + num(c.b) + "]"; }

void check_indices(const ControlMesh& mesh, std::span<const int32_t> colors) {
  for (int32_t c : colors)
    if (c < 0 || c >= mesh.num_colors()) invalid("color index " + std::to_string(c) + " is out of range");
}

}  // namespace

void blend_colors(ControlMesh& mesh, std::span<const int32_t> colors, Color target, double amount) {
  if (!(amount >= 0 && amount <= 1)) invalid("amount " + num(amount) + " is outside [0, 1]");
  if (!std::isfinite(target.r) || !std::isfinite(target.g) || !std::isfinite(target.b)) {
    invalid("color " + color_name(target) + " is not finite");
  }
  check_indices(mesh, colors);
  if (amount == 0) return;
  const auto a = static_cast<float>(amount);
  for (int32_t i : colors) {
    Color& c = mesh.colors[i];
    c = {(1 - a) * c.r + a * target.r, (1 - a) * c.g + a * target.g, (1 - a) * c.b + a * target.b};
  }
}

std::array<double, 3> transform_colors(ControlMesh& mesh, std::span<const int32_t> colors,
                                       Color seed, Color target) {
  const float t[3] = {target.r, target.g, target.b}, s[3] = {seed.r, seed.g, seed.b};
  const char* names[3] = {"red", "green", "blue"};
  std::array<double, 3> m{};
  for (int k = 0; k < 3; ++k) {
    if (!std::isfinite(t[k]) || t[k] < 0) invalid("color " + color_name(target) + " is not finite and non-negative");
    if (!(s[k] > 0) || !std::isfinite(s[k])) {
      invalid("the seed color " + color_name(seed) + " has no " + names[k] +
              ": TRANSFORM scales each channel by new / old and cannot map 0 to " + num(t[k]) +
              " (use blend)");
    }
    m[k] = double(t[k]) / double(s[k]);
  }
  check_indices(mesh, colors);
  for (int32_t i : colors) {
    Color& c = mesh.colors[i];
    c = {static_cast<float>(m[0] * c.r), static_cast<float>(m[1] * c.g), static_cast<float>(m[2] * c.b)};
  }
  return m;
}

}  // namespace subvec
