// `subvec filter` (docs/cli.md, docs/levels.md); the level options of `subvec vectorize` are in
// vectorize_options.cpp.
#include "pyramid_commands.h"

#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>

#include "subvec/core/error.h"
#include "subvec/io/svec.h"
#include "subvec/pyramid/pyramid.h"
#include "validators.h"

namespace subvec_cli {
namespace {

using subvec::Error;
using subvec::ErrorCode;

// "a,b,c" finite numbers; returns an error message or "" and fills `out`.
std::string parse_numbers(const std::string& text, std::vector<double>& out) {
  out.clear();
  std::stringstream in(text);
  std::string item;
  const std::string expected = "expected numbers separated by commas, got '" + text + "'";
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(v)) return expected;
    out.push_back(v);
  }
  if (out.empty() || text.back() == ',') return expected;
  return "";
}

struct FilterArgs {
  std::string input, output, eta_levels;
  double eta = 1;
  bool geometry = false, color = false;
  int object = -1;  // -1: the levels
};

void run_filter(const FilterArgs& a, bool eta_given) {
  subvec::svec_format_for(a.output);
  const subvec::VectorImage image = subvec::read_svec(a.input);
  std::vector<double> etas = {a.eta};
  if (!eta_given && !a.eta_levels.empty()) parse_numbers(a.eta_levels, etas);  // validated by CLI11
  std::optional<int> object;
  if (a.object >= 0) object = a.object;
  const int bands = subvec::filter_bands(image, object);
  if (bands >= 1 && static_cast<int>(etas.size()) > bands) {
    throw Error(ErrorCode::kInvalidArgument, "--eta-levels has " + std::to_string(etas.size()) +
                                                 " values but '" + a.input + "' has " +
                                                 std::to_string(bands) + (bands == 1 ? " band" : " bands"));
  }
  subvec::FilterOptions options;
  options.object = object;
  // Colors by default (the image's frequencies live there); --geometry-eta adds or, alone, selects
  // the positions.
  const bool color = a.color || !a.geometry;
  if (a.geometry) options.geometry_eta = etas;
  if (color) options.color_eta = etas;
  subvec::FilterReport report;
  const subvec::VectorImage out = subvec::filter(image, options, &report);
  subvec::write_svec(a.output, out);
  std::string list;
  for (size_t i = 0; i < etas.size(); ++i) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%s%g", i ? "," : "", etas[i]);
    list += buf;
  }
  const std::string what = object ? " of object " + std::to_string(*object) : "";
  std::printf("%s -> %s: %d bands%s, eta %s on %s%s\n", a.input.c_str(), a.output.c_str(), report.bands,
              what.c_str(), list.c_str(), a.geometry && color ? "geometry and color" : a.geometry ? "geometry" : "color",
              report.restored_vertices > 0
                  ? (", " + std::to_string(report.restored_vertices) + " vertices held back from folding").c_str()
                  : "");
}

}  // namespace

void add_pyramid_commands(CLI::App& app) {
  static FilterArgs fa;
  CLI::App* filter = app.add_subcommand(
      "filter", "Smooth or enhance a multilevel vector image through its pyramid (paper 6.4)");
  filter->add_option("input", fa.input, "Vector image with levels (vectorize --levels)")->required();
  filter->add_option("-o,--output", fa.output, "Output vector image (.svec or .svec.json)")->required();
  const CLI::Validator finite = finite_number();
  CLI::Option* eta = filter->add_option("--eta", fa.eta,
                                        "Detail scale for every band: < 1 smooths, > 1 enhances (default 1)")
                         ->check(finite);
  CLI::Option* eta_levels =
      filter
          ->add_option("--eta-levels", fa.eta_levels,
                       "Detail scale per band, finest first (a,b,...); a short list repeats its last value")
          ->check(CLI::Validator(
              [](std::string& text) {
                std::vector<double> v;
                return parse_numbers(text, v);
              },
              "A,B,...", "etas"));
  eta->excludes(eta_levels);
  filter->add_flag("--geometry-eta", fa.geometry,
                   "Scale the position details (alone: positions only; with --color-eta: both)");
  filter->add_flag("--color-eta", fa.color, "Scale the color details (the default when neither flag is given)");
  filter
      ->add_option("--object", fa.object,
                   "Filter object N alone, through a pyramid made from its own mesh (at least 2 bands)")
      ->check(CLI::NonNegativeNumber);
  filter->footer(
      "Examples:\n"
      "  subvec filter photo.svec -o smooth.svec --eta 0.3            # low-pass\n"
      "  subvec filter photo.svec -o sharp.svec --eta 1.8             # enhance color detail\n"
      "  subvec filter photo.svec -o calm.svec --eta 0.5 --geometry-eta --color-eta  # both\n"
      "  subvec filter photo.svec -o band.svec --eta-levels 0.2,1      # damp the finest band only\n"
      "  subvec filter moved.svec -o soft.svec --eta 0.3 --object 0     # one object");
  filter->callback([eta] { run_filter(fa, eta->count() > 0); });
}

}  // namespace subvec_cli
