// `subvec batch IN_DIR -o OUT_DIR` (docs/cli.md): vectorizes every image of a folder, several at
// once, into OUT_DIR/<name>.svec (and <name>.png with --render-png), and writes
// OUT_DIR/summary.csv.
//
// - Parallelism is across images: --jobs images at a time, each vectorized on --threads threads
//   (1 by default). Whole images in parallel share no work and scale better than the parallel
//   regions inside one vectorization (docs/python.md, "Batch timings").
// - Outputs are a function of the input and the options only (the library's outputs do not depend
//   on thread counts, and each image has one worker), so they are byte-identical for any --jobs.
// - Resumable: an image whose outputs exist and read back as valid is skipped (and measured again
//   for the summary). Every file is written to a temporary name and renamed, so an interrupted run
//   leaves only complete outputs.
// - One image failing does not stop the others; the command then lists the failures and exits 1.
// - MAE is measured on what was written: the .svec as read back, rendered at 1x against the input
//   (so a skipped image reports the same value as a fresh run).
#include "batch.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <new>
#include <string>
#include <thread>
#include <vector>

#include "subvec/core/error.h"
#include "subvec/core/metrics.h"
#include "subvec/io/file.h"
#include "subvec/io/image_io.h"
#include "subvec/io/svec.h"
#include "subvec/render/renderer.h"
#include "subvec/vectorize/vectorize.h"
#include "cancel.h"
#include "messages.h"
#include "progress.h"
#include "validators.h"
#include "vectorize_options.h"

namespace subvec_cli {
namespace {

namespace fs = std::filesystem;
using subvec::Error;
using subvec::ErrorCode;
using Clock = std::chrono::steady_clock;

struct BatchArgs {
  BatchArgs() { vectorize.options.threads = 1; }
  std::string input, output;
  int jobs = 0;  // 0: one per core
  // As `subvec vectorize` takes them (vectorize_options.h); batch sets the vertex count, the
  // levels and the threads per image (1 by default), and leaves the rest at their defaults.
  VectorizeParams vectorize;
  subvec::VectorizeOptions options;  // vectorize_options(vectorize), validated before any work
  const std::atomic<bool>* cancel = nullptr;  // Ctrl+C
  int64_t max_pixels = 0;  // --max-pixels (add_limit_options)
  bool render_png = false;
};

enum class Status { kPending, kOk, kSkipped, kFailed };

struct Item {
  fs::path input, svec, png;
  std::string conflict;  // non-empty: another input maps to the same output name
  // Results (one writer: the worker that took the item).
  Status status = Status::kPending;
  int width = 0, height = 0, vertices = 0, triangles = 0;
  double mae = 0, seconds = 0;
  std::string error;
};

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

bool is_image_file(const fs::path& p) {
  static const char* const kExtensions[] = {".png", ".jpg", ".jpeg", ".webp",
                                            ".tif", ".tiff", ".bmp"};
  const std::string ext = lower(p.extension().string());
  return std::any_of(std::begin(kExtensions), std::end(kExtensions),
                     [&](const char* e) { return ext == e; });
}

// The images of `dir` (not its subfolders), by name; outputs named after each stem.
std::vector<Item> list_items(const BatchArgs& a) {
  std::error_code ec;
  if (!fs::is_directory(a.input, ec)) {
    throw Error(ErrorCode::kIo, a.input + (fs::exists(a.input, ec) ? ": not a directory"
                                                                   : ": no such directory"));
  }
  std::vector<Item> items;
  for (fs::directory_iterator it(a.input, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code file_ec;
    if (!it->is_regular_file(file_ec) || !is_image_file(it->path())) continue;
    Item item;
    item.input = it->path();
    items.push_back(std::move(item));
  }
  if (ec) throw Error(ErrorCode::kIo, "cannot list '" + a.input + "': " + ec.message());
  if (items.empty()) {
    throw Error(ErrorCode::kInvalidArgument,
                "no images (.png, .jpg, .jpeg, .webp, .tif, .tiff, .bmp) in '" + a.input + "'");
  }
  std::sort(items.begin(), items.end(), [](const Item& x, const Item& y) {
    return x.input.filename().string() < y.input.filename().string();
  });
  std::map<std::string, std::string> first_with_stem;
  for (Item& item : items) {
    const std::string stem = item.input.stem().string();
    item.svec = fs::path(a.output) / (stem + ".svec");
    item.png = fs::path(a.output) / (stem + ".png");
    const auto [at, inserted] = first_with_stem.emplace(stem, item.input.filename().string());
    if (!inserted) {
      item.conflict = "its output " + stem + ".svec would be the output of " + at->second;
    }
  }
  return items;
}

// The outputs of a previous run, when they exist and read back as valid; nullptr otherwise.
std::unique_ptr<subvec::VectorImage> previous_output(const Item& item, bool render_png) {
  std::error_code ec;
  if (!fs::is_regular_file(item.svec, ec)) return nullptr;
  if (render_png && !fs::is_regular_file(item.png, ec)) return nullptr;
  try {
    auto image = std::make_unique<subvec::VectorImage>(subvec::read_svec(item.svec));
    if (render_png) {
      const subvec::Image8 png = subvec::read_image(item.png);
      if (png.width != image->width || png.height != image->height) return nullptr;
    }
    return image;
  } catch (const Error&) {
    return nullptr;  // damaged or foreign: made again
  }
}

void process(Item& item, const BatchArgs& a) {
  const auto start = Clock::now();
  if (!item.conflict.empty()) throw Error(ErrorCode::kInvalidArgument, item.conflict);
  const subvec::Image8 photo = subvec::read_image(item.input, a.max_pixels);
  item.width = photo.width;
  item.height = photo.height;

  std::unique_ptr<subvec::VectorImage> saved = previous_output(item, a.render_png);
  const bool skipped = saved != nullptr;
  if (saved && (saved->width != photo.width || saved->height != photo.height)) saved.reset();
  std::vector<uint8_t> bytes;
  if (!saved) {
    // The document `subvec vectorize` makes with the same options, levels included.
    subvec::VectorizeOptions options = a.options;
    options.cancel = a.cancel;
    const subvec::VectorImage vectorized = subvec::vectorize(photo, options);
    bytes = subvec::to_svec_binary(vectorized);
    // What the file holds (positions and colors on the .svec grids), measured and drawn below.
    saved = std::make_unique<subvec::VectorImage>(subvec::parse_svec_binary(bytes));
  }
  subvec::RenderOptions render_options;
  render_options.threads = a.options.threads;
  const subvec::Image8 rendered = subvec::render(*saved, render_options);
  const subvec::ImageDifference d = subvec::compare(photo, rendered);
  if (!bytes.empty()) {
    // The PNG first: an .svec without its PNG is made again, a PNG without its .svec too.
    if (a.render_png) subvec::write_png(item.png, rendered);
    subvec::write_file_atomic(item.svec, bytes);
  }
  item.vertices = saved->levels.front().num_vertices();
  item.triangles = saved->levels.front().num_triangles();
  item.mae = d.mae_mean;
  item.status = skipped && bytes.empty() ? Status::kSkipped : Status::kOk;
  item.seconds = std::chrono::duration<double>(Clock::now() - start).count();
}

// CSV field: quoted when it holds a comma, a quote or a line break (as Python's csv module does).
std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

const char* status_name(Status s) {
  switch (s) {
    case Status::kOk: return "ok";
    case Status::kSkipped: return "skipped";
    case Status::kFailed: return "failed";
    case Status::kPending: break;
  }
  return "pending";
}

std::string summary_csv(const std::vector<Item>& items) {
  std::string out = "image,output,width,height,vertices,triangles,mae,seconds,status,error\n";
  char buf[64];
  for (const Item& item : items) {
    const bool done = item.status == Status::kOk || item.status == Status::kSkipped;
    out += csv_field(item.input.filename().string()) + ",";
    out += (done ? csv_field(item.svec.filename().string()) : "") + ",";
    out += (done ? std::to_string(item.width) : "") + ",";
    out += (done ? std::to_string(item.height) : "") + ",";
    out += (done ? std::to_string(item.vertices) : "") + ",";
    out += (done ? std::to_string(item.triangles) : "") + ",";
    std::snprintf(buf, sizeof buf, "%.4f", item.mae);
    out += (done ? std::string(buf) : "") + ",";
    std::snprintf(buf, sizeof buf, "%.3f", item.seconds);
    out += std::string(buf) + ",";
    out += std::string(status_name(item.status)) + ",";
    out += csv_field(item.error) + "\n";
  }
  return out;
}

void run_batch(BatchArgs& a) {
  a.options = vectorize_options(a.vectorize);  // the library's ranges, as usage errors
  std::vector<Item> items = list_items(a);
  std::error_code ec;
  fs::create_directories(a.output, ec);
  if (ec || !fs::is_directory(a.output)) {
    throw Error(ErrorCode::kIo, "cannot create the output directory '" + a.output + "'" +
                                    (ec ? ": " + ec.message() : ""));
  }
  const auto start = Clock::now();
  const int count = static_cast<int>(items.size());
  const int cores = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const int jobs = std::min(count, a.jobs > 0 ? a.jobs : cores);

  // On a terminal: images done of all, a bar, elapsed seconds and the estimated time left.
  ProgressLine progress("batch", count, "images", {"skipped", "failed"});
  // Ctrl+C: the images being vectorized stop, no new one starts, and what is done stays done.
  const CancelOnInterrupt interrupt;
  a.cancel = interrupt.flag();
  std::atomic<int> next{0};
  const auto worker = [&] {
    for (int i = next++; i < count && !interrupt.cancelled(); i = next++) {
      Item& item = items[size_t(i)];
      const auto item_start = Clock::now();
      try {
        process(item, a);
      } catch (const Error& e) {
        if (e.code() == ErrorCode::kCancelled) break;
        item.error = one_line(with_flag_names(e.what()));  // e.g. the memory check
      } catch (const std::bad_alloc&) {
        item.error = "out of memory";
      } catch (const std::exception& e) {
        item.error = one_line(e.what());
      }
      if (!item.error.empty()) {
        item.status = Status::kFailed;
        item.seconds = std::chrono::duration<double>(Clock::now() - item_start).count();
      }
      progress.advance(item.status == Status::kSkipped  ? 0
                       : item.status == Status::kFailed ? 1
                                                        : -1);
    }
  };
  std::vector<std::thread> pool;
  for (int j = 1; j < jobs; ++j) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  progress.finish();
  if (interrupt.cancelled()) {
    int done = 0;
    for (const Item& item : items) done += item.status == Status::kOk || item.status == Status::kSkipped;
    throw Error(ErrorCode::kCancelled, "cancelled: " + std::to_string(done) + " of " + std::to_string(count) +
                                           " images done (run again to resume)");
  }

  const std::string csv = summary_csv(items);
  const fs::path csv_path = fs::path(a.output) / "summary.csv";
  subvec::write_file_atomic(
      csv_path, std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(csv.data()), csv.size()));

  int ok = 0, skipped = 0, failed = 0;
  for (const Item& item : items) {
    ok += item.status == Status::kOk;
    skipped += item.status == Status::kSkipped;
    failed += item.status == Status::kFailed;
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  std::printf("%d %s: %d vectorized, %d skipped (already done), %d failed in %.1f s (%d at a time); "
              "summary in %s\n",
              count, count == 1 ? "image" : "images", ok, skipped, failed, seconds, jobs,
              csv_path.string().c_str());
  std::fflush(stdout);
  if (failed == 0) return;
  std::fflush(stdout);
  for (const Item& item : items) {
    if (item.status == Status::kFailed) {
      std::fprintf(stderr, "subvec: %s: %s\n", item.input.string().c_str(), item.error.c_str());
    }
  }
  // main() prints this last line and exits with status 1.
  throw Error(ErrorCode::kInvalidArgument,
              std::to_string(failed) + " of " + std::to_string(count) +
                  " images failed (listed above; the others are done)");
}

}  // namespace

void add_batch_command(CLI::App& app) {
  static BatchArgs ba;  // lives as long as the program: the callback runs after parsing
  CLI::App* batch = app.add_subcommand(
      "batch", "Vectorize every image of a folder, several at once, with a CSV summary");
  batch->add_option("input", ba.input, "Folder of images (PNG, JPEG, WebP, TIFF, BMP)")->required();
  batch->add_option("-o,--output", ba.output,
                    "Output folder (created): NAME.svec per image, summary.csv")
      ->required();
  batch->add_option("--jobs", ba.jobs, "Images vectorized at once; 0 (default) one per core")
      ->check(CLI::Range(0, 1024));
  batch->add_option("--threads", ba.vectorize.options.threads, "Threads per image (default 1; 0: all cores)")
      ->check(integer());
  add_vertex_count_options(batch, ba.vectorize);
  add_quality_options(batch, ba.vectorize);
  add_level_options(batch, ba.vectorize, /*levels_only=*/true);
  add_limit_options(batch, ba.vectorize, ba.max_pixels);
  batch->add_flag("--render-png", ba.render_png,
                  "Also write NAME.png: the vectorized image rendered at its own size");
  batch->footer(
      "Outputs that exist and read back as valid are kept (the image is skipped), so an\n"
      "interrupted run resumes; remove them to vectorize again. Exit status 1 when an image\n"
      "failed (the others are still done; the failures are listed on stderr).\n"
      "Examples:\n"
      "  subvec batch photos/ -o vectors/\n"
      "  subvec batch photos/ -o vectors/ --jobs 2 --ratio 0.02 --render-png");
  batch->callback([] { run_batch(ba); });
}

}  // namespace subvec_cli
