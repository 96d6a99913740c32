// The editor page's built files (web/dist), embedded in the binary at build time
// (apps/serve/embed_assets.cmake), so that `subvec serve` needs no Node and no files at run time.
#pragma once

#include <cstddef>
#include <string>

namespace subvec_serve {

struct EmbeddedAsset {
  const char* path;          // relative to web/dist, e.g. "index.html", "assets/editor.js"
  const char* content_type;
  const unsigned char* data;
  size_t size;
};

// The asset at `path`, or nullptr.
const EmbeddedAsset* find_asset(const std::string& path);

}  // namespace subvec_serve
