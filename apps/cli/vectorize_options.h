// The vectorization options that `subvec vectorize`, `subvec batch` and `subvec serve` share,
// registered in one place onto the library's parameter struct (subvec::VectorizeOptions), so that
// they make the same document with the same options (tests/python/test_batch.py and
// tests/unit/serve check that the files are identical). Defaults come from the struct and ranges
// from subvec::validate(): the flags parse types only, and vectorize_options() reports the
// library's message with the field names replaced by the flags.
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "subvec/vectorize/vectorize.h"

namespace subvec_cli {

struct VectorizeParams {
  subvec::VectorizeOptions options;         // the fields the flags fill, at the library's defaults
  std::string fit = "pixels";               // --fit: pixels or vertices (checked by CLI11)
  std::string segment;                      // --segment X,Y,W,H, or empty
  std::vector<std::string> feature_levels;  // --feature-level ID=L
};

// Adds --ratio and --vertices (one or the other) to `command`.
void add_vertex_count_options(CLI::App* command, VectorizeParams& params);

// Adds the options that shape the result (--fit, --l1-iterations, --relocate, --refine, --grid-step, the
// feature detector's and --max-feature-error).
void add_quality_options(CLI::App* command, VectorizeParams& params);

// Adds --levels and, unless `levels_only`, --saliency-weight, --level-reduction and --feature-level.
void add_level_options(CLI::App* command, VectorizeParams& params, bool levels_only = false);

// Adds --max-pixels (into `max_pixels`, which starts at subvec::kDefaultMaxInputPixels: the
// reader's limit) and --max-memory (the library's max_memory; sizes such as 6G or 800MB).
void add_limit_options(CLI::App* command, VectorizeParams& params, int64_t& max_pixels);

// Everything `subvec vectorize` takes that shapes the document: the above, --segment and --threads.
void add_vectorize_options(CLI::App* command, VectorizeParams& params);

// Parses "X,Y,W,H" (integers); returns an error message, or "" and fills `r`. Whether the
// rectangle lies inside the image is the library's check, once the image is read.
std::string parse_rect(const std::string& text, subvec::PixelRect& r);

// The library's options for `params` (no progress callback), checked by subvec::validate(). Its
// error becomes a CLI::ValidationError (exit status 105) that names the flag, not the field.
subvec::VectorizeOptions vectorize_options(const VectorizeParams& params);

// `message` with a leading library field name ("levels.reduction must ...") replaced by its flag.
std::string with_flag_names(const std::string& message);

}  // namespace subvec_cli
