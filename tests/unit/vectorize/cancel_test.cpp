// The cancel flag inside the long stages (VectorizeOptions::cancel, and the `cancel` of
// SimplifyOptions, RefineOptions, ColorFitOptions and LevelOptions): each stage function checks it
// itself, not only vectorize() between stages, so that Ctrl+C does not wait for a stage of seconds.
// The stage functions are called directly: a stage that does not check its flag fails here.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <string>
#include <vector>

#include "subvec/core/error.h"
#include "subvec/mesh/validate.h"
#include "subvec/vectorize/features.h"
#include "subvec/vectorize/fit.h"
#include "subvec/vectorize/initial_mesh.h"
#include "subvec/vectorize/levels.h"
#include "subvec/vectorize/refine.h"
#include "subvec/vectorize/simplify.h"
#include "subvec/vectorize/vectorize.h"
#include "support/synthetic.h"
#include "vectorize/simplify_p.h"

namespace subvec {
namespace {

using test::textured_disk;

bool same_mesh(const ControlMesh& a, const ControlMesh& b) {
  return a.positions == b.positions && a.colors == b.colors && a.triangles == b.triangles &&
         a.triangle_colors == b.triangle_colors;
}

// Runs job() and returns whether it threw Error(kCancelled); any other outcome is a failure.
template <class Job>
bool cancelled(const Job& job) {
  try {
    job();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kCancelled) << e.what();
    return e.code() == ErrorCode::kCancelled;
  }
  return false;
}

class Cancel : public ::testing::Test {
 protected:
  const Image8 img_ = textured_disk(96, 80);
  const ControlMesh dense_ = build_initial_mesh(img_, detect_features(img_));
  std::atomic<bool> set_{true}, unset_{false};

  ControlMesh simplified(int vertices) const {
    ControlMesh mesh = dense_;
    SimplifyOptions options;
    options.target_vertices = vertices;
    simplify(mesh, img_.width, img_.height, options);
    return mesh;
  }
};

// Both phases (the region-parallel one, from over 16 times the target, and the global one) and the
// serial reference of the regions stop, and leave the mesh as it was. (Near the target there is no
// region phase, and the serial reference does nothing.)
TEST_F(Cancel, SimplifyChecksTheFlag) {
  ASSERT_GT(dense_.num_vertices(), 2000);
  using detail::SimplifySchedule;
  for (const int target : {dense_.num_vertices() / 2, 100}) {
    for (const SimplifySchedule schedule :
         {SimplifySchedule::kRegionsThenGlobal, SimplifySchedule::kGlobal, SimplifySchedule::kRegionsSerial}) {
      if (schedule == SimplifySchedule::kRegionsSerial && 16 * target >= dense_.num_vertices()) continue;
      SCOPED_TRACE("target " + std::to_string(target) + ", schedule " + std::to_string(int(schedule)));
      ControlMesh mesh = dense_;
      SimplifyOptions options;
      options.target_vertices = target;
      options.cancel = &set_;
      EXPECT_TRUE(cancelled([&] { detail::simplify_scheduled(mesh, img_.width, img_.height, options, schedule); }));
      EXPECT_TRUE(same_mesh(mesh, dense_));
    }
  }
  // A flag that is not set changes nothing.
  ControlMesh with_flag = dense_, without = dense_;
  SimplifyOptions options;
  options.target_vertices = 100;
  simplify(without, img_.width, img_.height, options);
  options.cancel = &unset_;
  simplify(with_flag, img_.width, img_.height, options);
  EXPECT_TRUE(same_mesh(with_flag, without));
}

// The flip passes check it, and so do the vertex moves (alone when there are no flip passes).
TEST_F(Cancel, RefineChecksTheFlag) {
  const ControlMesh start = simplified(150);
  for (const int flip_passes : {4, 0}) {
    SCOPED_TRACE("flip_passes " + std::to_string(flip_passes));
    ControlMesh mesh = start;
    RefineOptions options;
    options.flip_passes = flip_passes;
    options.cancel = &set_;
    EXPECT_TRUE(cancelled([&] { refine_mesh(mesh, img_, options); }));
    EXPECT_NO_THROW(validate_level(mesh, img_.width, img_.height));
  }
  ControlMesh with_flag = start, without = start;
  RefineOptions options;
  const RefineStats a = refine_mesh(without, img_, options);
  options.cancel = &unset_;
  const RefineStats b = refine_mesh(with_flag, img_, options);
  EXPECT_GT(a.flips + a.moves, 0);
  EXPECT_EQ(b.flips, a.flips);
  EXPECT_TRUE(same_mesh(with_flag, without));
}

// Before the solve (at the defaults: no relocation, no reweighting), and so with relocation and
// reweighting asked for too; the mesh stays as it was.
TEST_F(Cancel, FitChecksTheFlag) {
  const ControlMesh start = simplified(150);
  ColorFitOptions options;
  options.cancel = &set_;
  ControlMesh mesh = start;
  EXPECT_TRUE(cancelled([&] { fit_colors(mesh, img_.width, img_.height, img_, options); }));
  EXPECT_TRUE(same_mesh(mesh, start));
  options.relocate_iterations = 2;
  options.l1_iterations = 1;
  EXPECT_TRUE(cancelled([&] { fit_colors(mesh, img_.width, img_.height, img_, options); }));
  EXPECT_TRUE(same_mesh(mesh, start));
  ControlMesh with_flag = start, without = start;
  options.cancel = nullptr;
  fit_colors(without, img_.width, img_.height, img_, options);
  options.cancel = &unset_;
  fit_colors(with_flag, img_.width, img_.height, img_, options);
  EXPECT_FALSE(same_mesh(without, start));
  EXPECT_TRUE(same_mesh(with_flag, without));
}

// Before each coarser level; with one level there is nothing long to stop.
TEST_F(Cancel, LevelsCheckTheFlag) {
  VectorImage image;
  image.width = img_.width;
  image.height = img_.height;
  image.levels.push_back(simplified(300));
  fit_colors(image.levels[0], img_.width, img_.height, img_);
  LevelOptions options;
  options.levels = 3;
  options.cancel = &set_;
  VectorImage cancelled_image = image;
  EXPECT_TRUE(cancelled([&] { build_levels(cancelled_image, img_, options); }));
  EXPECT_EQ(cancelled_image.levels.size(), 1u);
  options.levels = 1;
  EXPECT_NO_THROW(build_levels(cancelled_image, img_, options));
  options.levels = 3;
  options.cancel = &unset_;
  build_levels(image, img_, options);
  EXPECT_EQ(image.levels.size(), 3u);
}

// vectorize() passes its flag into each long stage: set as a stage starts (from the progress
// callback, after vectorize()'s own check), the job stops inside that stage. The report's stage
// times end before it (a stage's time is recorded when it returns), and no later stage starts.
TEST_F(Cancel, VectorizeStopsInsideTheStageThatIsRunning) {
  const std::vector<std::string> all = {"features", "mesh", "simplify", "refine", "fit", "levels"};
  for (size_t stop = 2; stop < all.size(); ++stop) {
    SCOPED_TRACE(all[stop]);
    std::atomic<bool> flag{false};
    std::vector<std::string> seen;
    VectorizeOptions options;
    options.cancel = &flag;
    options.progress = [&](const std::string& stage, double) {
      seen.push_back(stage);
      if (stage == all[stop]) flag = true;
    };
    VectorizeReport report;
    EXPECT_TRUE(cancelled([&] { vectorize(img_, options, &report); }));
    EXPECT_EQ(seen, std::vector<std::string>(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(stop) + 1));
    std::vector<std::string> timed;
    for (const StageTime& t : report.stages) timed.push_back(t.stage);
    EXPECT_EQ(timed, std::vector<std::string>(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(stop)));
  }
}

}  // namespace
}  // namespace subvec
