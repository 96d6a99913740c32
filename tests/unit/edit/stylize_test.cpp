// Stylization (edit/stylize.h): saliency, the choice of features, determinism for a seed, and the
// strokes showing up in renders.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <vector>

#include "subvec/core/error.h"
#include "subvec/edit/selection.h"
#include "subvec/edit/stylize.h"
#include "subvec/mesh/validate.h"
#include "subvec/render/renderer.h"
#include "support/synthetic.h"

namespace subvec {
namespace {

VectorImage make_image(bool with_saliency) {
  VectorImage img = test::make_synthetic_image({.width = 200, .height = 160, .vertices = 1200});
  if (with_saliency) {
    const std::vector<double> s = feature_saliency(img, 0);
    for (size_t f = 0; f < s.size(); ++f) img.levels[0].features[f].saliency = s[f];
  }
  return img;
}

// Saliency unknown (0) in the file.
const VectorImage& image() {
  static const VectorImage img = make_image(false);
  return img;
}

// The same with the saliency stored (stylizing it skips the render for the contrast).
const VectorImage& image_with_saliency() {
  static const VectorImage img = make_image(true);
  return img;
}

int num_pieces(const VectorImage& img) {
  const ControlMesh& m = img.levels[0];
  const MeshTopology t = validate_level(m, img.width, img.height);
  int n = 0;
  for (const Feature& f : m.features) n += static_cast<int>(feature_pieces(t, f).size());
  return n;
}

bool same(const std::vector<Stroke>& a, const std::vector<Stroke>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i].points != b[i].points || a[i].width != b[i].width || a[i].color != b[i].color ||
        a[i].taper != b[i].taper || a[i].level != b[i].level)
      return false;
  }
  return true;
}

TEST(Stylize, SaliencyIsLengthPlusWeightedContrastWhenUnknown) {
  const std::vector<double> s = feature_saliency(image(), 0);
  const std::vector<double> length_only = feature_saliency(image(), 0, 0.0);
  ASSERT_EQ(s.size(), image().levels[0].features.size());
  for (size_t f = 0; f < s.size(); ++f) {
    EXPECT_GT(length_only[f], 10) << "feature " << f;           // curves tens of pixels long
    EXPECT_GT(s[f], length_only[f] + 2) << "feature " << f;     // the colors jump across tears
  }
  VectorImage stored = image();
  stored.levels[0].features[0].saliency = 1234.5;
  EXPECT_EQ(feature_saliency(stored, 0)[0], 1234.5);
  EXPECT_EQ(feature_saliency(stored, 0)[1], s[1]);
}

TEST(Stylize, FeaturesAtOrAboveTheThresholdAlwaysGetStrokes) {
  StylizeOptions o;
  o.threshold = 0;
  StylizeReport r;
  const std::vector<Stroke> all = stylize(image(), o, &r);
  EXPECT_TRUE(same(all, stylize(image_with_saliency(), o)));
  EXPECT_EQ(r.in_region, static_cast<int>(image().levels[0].features.size()));
  EXPECT_EQ(r.above, r.in_region);
  EXPECT_EQ(static_cast<int>(all.size()), num_pieces(image()));
  for (const Stroke& s : all) {
    EXPECT_GE(s.width, o.min_width);
    EXPECT_LE(s.width, o.max_width);
    EXPECT_EQ(s.taper, o.taper);
  }
  // Nothing above a huge threshold, nothing chosen at probability 0.
  o.threshold = 1e9;
  o.probability = 0;
  EXPECT_TRUE(stylize(image(), o).empty());
  // A region away from every feature holds none.
  StylizeOptions corner;
  corner.roi = Rect{0, 0, 4, 4};
  stylize(image(), corner, &r);
  EXPECT_EQ(r.in_region, 0);
}

TEST(Stylize, LongerFeaturesGetWiderStrokes) {
  StylizeOptions o;
  o.threshold = 0;
  const VectorImage& img = image();
  const std::vector<double> length = feature_saliency(img, 0, 0.0);
  const std::vector<Stroke> strokes = stylize(img, o);
  // Strokes come in feature order; match them to features by their first point. Every stroke
  // must match one, and the widths of matched features must follow their lengths.
  ASSERT_FALSE(strokes.empty());
  std::vector<float> width(img.levels[0].features.size(), 0);
  std::vector<char> matched(width.size(), 0);
  size_t matched_strokes = 0;
  for (const Stroke& s : strokes) {
    bool found = false;
    for (size_t f = 0; f < width.size(); ++f) {
      for (int32_t v : img.levels[0].features[f].vertices) {
        if (img.levels[0].positions[v] == s.points.front()) {
          width[f] = s.width;
          matched[f] = 1;
          found = true;
        }
      }
    }
    matched_strokes += found;
  }
  EXPECT_EQ(matched_strokes, strokes.size());
  int compared = 0;
  for (size_t a = 0; a < width.size(); ++a)
    for (size_t b = 0; b < width.size(); ++b)
      if (matched[a] && matched[b] && length[a] > length[b]) {
        EXPECT_GE(width[a], width[b]) << "features " << a << " and " << b;
        ++compared;
      }
  EXPECT_GT(compared, 0);
}

TEST(Stylize, TheChoiceBelowTheThresholdIsDeterministicForASeed) {
  StylizeOptions o;
  o.threshold = 1e9;  // every feature below: each is a coin flip
  o.probability = 0.5;
  std::set<size_t> outcomes;
  for (uint64_t seed = 1; seed <= 24; ++seed) {
    o.seed = seed;
    const std::vector<Stroke> a = stylize(image_with_saliency(), o),
                              b = stylize(image_with_saliency(), o);
    EXPECT_TRUE(same(a, b)) << "seed " << seed;
    outcomes.insert(a.size());
  }
  EXPECT_GT(outcomes.size(), 1u);
}

TEST(Stylize, StrokesAppearInRenders) {
  VectorImage styled = image();
  StylizeOptions o;
  o.threshold = 0;
  o.color = {255, 0, 255};
  o.min_width = o.max_width = 3;
  styled.strokes = stylize(styled, o);
  ASSERT_FALSE(styled.strokes.empty());
  validate(styled);
  const Image8 plain = render(image(), RenderOptions{});
  const Image8 drawn = render(styled, RenderOptions{});
  ASSERT_EQ(plain.pixels.size(), drawn.pixels.size());
  int changed = 0, magenta = 0;
  for (size_t i = 0; i < plain.pixels.size(); i += 3) {
    changed += plain.pixels[i] != drawn.pixels[i] || plain.pixels[i + 1] != drawn.pixels[i + 1];
    magenta += drawn.pixels[i] == 255 && drawn.pixels[i + 1] == 0 && drawn.pixels[i + 2] == 255;
  }
  EXPECT_GT(changed, 500);
  EXPECT_GT(magenta, 200);
  // Another level's strokes are not drawn over level 0.
  for (Stroke& s : styled.strokes) s.level = 1;
  styled.levels.push_back(styled.levels[0]);
  EXPECT_EQ(render(styled, RenderOptions{}).pixels, plain.pixels);
}

TEST(Stylize, BadOptionsAreRefused) {
  StylizeOptions o;
  o.level = 3;
  EXPECT_THROW(stylize(image(), o), Error);
  o.level = 0;
  o.roi = Rect{0, 0, 0, 10};
  EXPECT_THROW(stylize(image(), o), Error);
  o.roi.reset();
  o.probability = 2;
  EXPECT_THROW(stylize(image(), o), Error);
  o.probability = 0.3;
  o.threshold = -5;  // saliency is never negative: the editor accepted this before (issue 29)
  try {
    stylize(image(), o);
    ADD_FAILURE() << "a negative threshold was accepted";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "stylize: the threshold -5 is negative (saliency is 0 or more)");
  }
}

// apply_stylize replaces the level's strokes in the region: twice is once, a second region adds
// to the first, another level's strokes stay.
TEST(Stylize, ApplyReplacesTheStrokesOfTheRegion) {
  StylizeOptions o;
  VectorImage once = image_with_saliency();
  const StylizeReport first = apply_stylize(once, o);
  ASSERT_GT(first.strokes, 0);
  EXPECT_EQ(first.replaced, 0);
  VectorImage twice = once;
  const StylizeReport second = apply_stylize(twice, o);
  EXPECT_EQ(second.replaced, first.strokes);
  ASSERT_EQ(twice.strokes.size(), once.strokes.size());
  for (size_t i = 0; i < once.strokes.size(); ++i) EXPECT_EQ(twice.strokes[i].points, once.strokes[i].points);

  VectorImage halves = image_with_saliency();
  StylizeOptions left = o, right = o;
  left.roi = Rect{0, 0, 100, 160};
  right.roi = Rect{100, 0, 100, 160};
  const StylizeReport a = apply_stylize(halves, left);
  const StylizeReport b = apply_stylize(halves, right);
  EXPECT_GT(a.strokes, 0);
  EXPECT_GT(b.strokes, 0);
  EXPECT_EQ(static_cast<int>(halves.strokes.size()), a.strokes + b.strokes - b.replaced);

  VectorImage other = image_with_saliency();
  Stroke kept;
  kept.level = 1;
  kept.points = {{10, 10}, {50, 50}};
  other.strokes.push_back(kept);
  apply_stylize(other, o);
  apply_stylize(other, o);
  EXPECT_EQ(std::count_if(other.strokes.begin(), other.strokes.end(), [](const Stroke& s) { return s.level == 1; }), 1);
}

}  // namespace
}  // namespace subvec
