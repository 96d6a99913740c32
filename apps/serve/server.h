// The HTTP front end of `subvec serve` (docs/serve.md): serves the editor page (built assets
// embedded in the binary) and a small JSON + binary API over an Editor (editor.h).
//
// Boundaries. Requests are bounded (a 64 KiB body, the header limits of cpp-httplib), every error
// is a JSON object {"error": "..."} with an HTTP status (400 malformed request, 403 foreign Host,
// 404 unknown path or session, 409 stale version, 413 too large, 415 not JSON, 422 an edit the
// image does not allow, 503 still vectorizing). The server reads
// the input file once and writes only the output file the user named with -o; downloads are
// built in memory. Bound to loopback (the default), it answers only requests whose Host header
// names a loopback address, so a web page elsewhere cannot reach it through DNS rebinding, and
// changes only through POST with a JSON body, which a foreign page cannot send without CORS.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "subvec/vectorize/vectorize.h"

namespace subvec_serve {

struct ServeOptions {
  std::filesystem::path input;                  // vector image, or a raster image to vectorize
  std::optional<std::filesystem::path> output;  // where "Save" writes (.svec or .svec.json)
  std::string host = "127.0.0.1";
  int port = 8080;                              // 0: any free port
  // Vectorization of a raster input: the document `subvec vectorize` makes with the same options,
  // levels included (its progress and cancel flag are the server's own).
  subvec::VectorizeOptions vectorize;
  int64_t max_pixels = subvec::kDefaultMaxInputPixels;
};

class EditorServer {
 public:
  explicit EditorServer(ServeOptions options);
  ~EditorServer();
  EditorServer(const EditorServer&) = delete;
  EditorServer& operator=(const EditorServer&) = delete;

  // Reads the input (a raster input starts vectorizing in the background) and binds the port.
  // Throws subvec::Error for an unreadable input or a port that cannot be bound.
  void start();
  int port() const;
  std::string url() const;
  // Serves until stop() (from another thread or a signal handler).
  void run();
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Whether a file starts like a raster image (PNG, JPEG, WebP, TIFF, BMP) rather than a vector image.
bool looks_like_raster(const std::filesystem::path& path);

}  // namespace subvec_serve
