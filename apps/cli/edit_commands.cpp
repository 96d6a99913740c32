// `subvec edit` and `subvec stylize` (docs/cli.md, docs/editing.md): parse options, call the
// edit library, write the result atomically.
#include "edit_commands.h"

#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "subvec/core/error.h"
#include "subvec/edit/ops.h"
#include "subvec/edit/stylize.h"
#include "subvec/io/file.h"
#include "subvec/io/svec.h"
#include "subvec/mesh/validate.h"
#include "validators.h"

namespace subvec_cli {
namespace {

using subvec::Error;
using subvec::ErrorCode;

constexpr int64_t kMaxOpsBytes = int64_t{64} << 20;

struct EditArgs {
  std::string input, output, ops;
  bool verbose = false;
};

struct StylizeArgs {
  std::string input, output, roi;
  int level = 0;
  double threshold = 0;
  bool threshold_given = false;
  uint64_t seed = 1;
  double probability = 0.3;
  int object = -1;  // -1: the level's own mesh
};

// Parses "X,Y,W,H" (W, H > 0); returns an error message, or "" and fills `r`.
std::string parse_roi(const std::string& text, subvec::Rect& r) {
  std::vector<double> v;
  std::stringstream in(text);
  std::string item;
  const std::string expected = "expected four numbers X,Y,W,H, got '" + text + "'";
  while (std::getline(in, item, ',')) {
    const char* begin = item.c_str();
    char* end = nullptr;
    const double x = std::strtod(begin, &end);
    if (item.empty() || end == begin || *end != '\0' || !std::isfinite(x)) return expected;
    v.push_back(x);
  }
  if (v.size() != 4 || (!text.empty() && text.back() == ',')) return expected;
  if (!(v[2] > 0) || !(v[3] > 0)) return "the region needs W > 0 and H > 0, got '" + text + "'";
  r = {v[0], v[1], v[2], v[3]};
  return "";
}

void run_edit(const EditArgs& a) {
  subvec::svec_format_for(a.output);  // rejects an unknown extension before any work
  subvec::VectorImage image = subvec::read_svec(a.input);
  const std::vector<uint8_t> bytes = subvec::read_file(a.ops, kMaxOpsBytes);
  std::vector<std::string> log;
  try {
    const std::vector<subvec::EditOp> ops =
        subvec::parse_edit_ops(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
    log = subvec::apply_edit_ops(image, ops);
  } catch (const Error& e) {
    throw Error(e.code(), a.ops + ": " + e.what());
  }
  subvec::write_svec(a.output, image);
  if (a.verbose)
    for (const std::string& line : log) std::printf("%s\n", line.c_str());
}

void run_stylize(const StylizeArgs& a) {
  subvec::svec_format_for(a.output);
  subvec::VectorImage image = subvec::read_svec(a.input);
  subvec::StylizeOptions options;
  options.level = a.level;
  if (!a.roi.empty()) {
    subvec::Rect r;
    parse_roi(a.roi, r);  // validated by CLI11
    options.roi = r;
  }
  if (a.threshold_given) options.threshold = a.threshold;
  options.seed = a.seed;
  options.probability = a.probability;
  if (a.object >= 0) options.object = a.object;
  const int num_levels = static_cast<int>(image.levels.size());
  if (a.level >= num_levels) {
    throw Error(ErrorCode::kInvalidArgument,
                "--level " + std::to_string(a.level) + " is out of range: '" + a.input + "' has " +
                    std::to_string(num_levels) + (num_levels == 1 ? " level" : " levels"));
  }
  const subvec::StylizeReport report = subvec::apply_stylize(image, options);
  subvec::write_svec(a.output, image);
  std::printf(
      "%d strokes on %d of %d features in the region (threshold %.1f: %d at or above, %d of %d "
      "below chosen with seed %llu)%s\n",
      report.strokes, report.above + report.chosen, report.in_region, report.threshold,
      report.above, report.chosen, report.in_region - report.above,
      static_cast<unsigned long long>(a.seed),
      report.replaced > 0 ? ("; replacing " + std::to_string(report.replaced) + " earlier strokes").c_str() : "");
}

}  // namespace

void add_edit_commands(CLI::App& app) {
  // The arguments live as long as the program: the callbacks run after parsing.
  static EditArgs ea;
  static StylizeArgs sa;

  CLI::App* edit = app.add_subcommand(
      "edit", "Edit shapes and colors of a vector image with mouse-like operations from a JSON file");
  edit->add_option("input", ea.input, "Vector image (.svec or .svec.json)")->required();
  edit->add_option("-o,--output", ea.output, "Output vector image (.svec or .svec.json)")->required();
  edit->add_option("--ops", ea.ops, "Operations: a JSON array (docs/editing.md)")->required();
  edit->add_flag("-v,--verbose", ea.verbose, "Print what each operation selected and did");
  edit->footer(
      "Operations, in image pixels (x right, y down), each with an optional \"level\":\n"
      "  {\"op\":\"drag\",\"select\":\"vertex\",\"from\":[x,y],\"to\":[x,y]}\n"
      "  {\"op\":\"drag\",\"select\":\"feature\",\"from\":[x,y],\"to\":[x,y],\"sigma\":20}\n"
      "  {\"op\":\"move-feature\",\"at\":[x,y],\"translate\":[dx,dy],\"rotate\":degrees}\n"
      "  {\"op\":\"color\",\"mode\":\"blend\",\"at\":[x,y],\"select\":\"vertex\",\"radius\":r,"
      "\"color\":[r,g,b],\"amount\":a}\n"
      "  {\"op\":\"color\",\"mode\":\"transform\",\"at\":[x,y],\"select\":\"feature\",\"radius\":r,"
      "\"color\":[r,g,b]}\n"
      "Examples:\n"
      "  subvec edit apple.svec -o edited.svec --ops ops.json\n"
      "  subvec edit apple.svec -o edited.svec.json --ops ops.json -v");
  edit->callback([] { run_edit(ea); });

  CLI::App* stylize = app.add_subcommand(
      "stylize", "Add strokes along the salient features of a vector image (paper 6.3)");
  stylize->add_option("input", sa.input, "Vector image (.svec or .svec.json)")->required();
  stylize->add_option("-o,--output", sa.output, "Output vector image (.svec or .svec.json)")->required();
  stylize->add_option("--level", sa.level, "Level of detail, 0 (the finest) by default")
      ->check(CLI::Range(0, subvec::Limits::kMaxLevels - 1));
  stylize
      ->add_option("--roi", sa.roi,
                   "Region of interest X,Y,W,H in image pixels (default: the whole image)")
      ->check(CLI::Validator(
          [](std::string& text) {
            subvec::Rect r;
            return parse_roi(text, r);
          },
          "X,Y,W,H", "roi"));
  CLI::Option* threshold =
      stylize->add_option("--threshold", sa.threshold,
                          "Saliency threshold; features at or above it always get a stroke "
                          "(default: the median over the region)")
          ->check(finite_number());
  stylize->add_option("--seed", sa.seed, "Seed for choosing features below the threshold (default 1)");
  stylize
      ->add_option("--probability", sa.probability,
                   "Chance that a feature below the threshold gets a stroke (default 0.3)")
      ->check(CLI::Range(0.0, 1.0));
  stylize
      ->add_option("--object", sa.object,
                   "Stroke the features of object N (its strokes move with it; --level is then "
                   "the object's)")
      ->check(CLI::NonNegativeNumber);
  stylize->footer(
      "Examples:\n"
      "  subvec stylize apple.svec -o styled.svec\n"
      "  subvec stylize apple.svec -o styled.svec --roi 100,80,300,300 --threshold 150 --seed 7\n"
      "  subvec stylize moved.svec -o styled.svec --object 0");
  stylize->callback([threshold] {
    sa.threshold_given = threshold->count() > 0;
    run_stylize(sa);
  });
}

}  // namespace subvec_cli
