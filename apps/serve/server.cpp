// The HTTP front end of `subvec serve`: routes, request parsing, binary frames, downloads.
#include "server.h"

#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <mutex>
#include <optional>
#include <thread>

#include <nlohmann/json.hpp>
#include <zlib.h>

#include "assets.h"
#include "editor.h"
#include "subvec/mesh/validate.h"
#include "subvec/core/error.h"
#include "subvec/export/export.h"
#include "subvec/io/image_io.h"
#include "subvec/io/svec.h"
#include "subvec/render/renderer.h"

// After the library headers: <httplib.h> brings <resolv.h>, whose _res macro breaks Eigen.
#include <httplib.h>

namespace subvec_serve {

using nlohmann::json;
using subvec::Error;
using subvec::ErrorCode;

namespace {

constexpr size_t kMaxBody = 64 * 1024;

// ---- binary frames -------------------------------------------------------------------------
// A frame is "SVB1", the byte length of a JSON header (u32, little-endian), the header padded
// with spaces to a multiple of 4 bytes, then the sections the header lists ("sections": name,
// type f32 / u32 / i16 / u8, count), each padded with zeros to a multiple of 4 bytes. The page reads the
// sections as typed arrays without copying.
class Frame {
 public:
  template <class T>
  void add(const std::string& name, const std::vector<T>& values) {
    static_assert(std::is_same_v<T, float> || std::is_same_v<T, uint32_t> ||
                  std::is_same_v<T, int16_t> || std::is_same_v<T, uint8_t>);
    const char* type = std::is_same_v<T, float>      ? "f32"
                       : std::is_same_v<T, uint32_t> ? "u32"
                       : std::is_same_v<T, int16_t>  ? "i16"
                                                     : "u8";
    sections_.push_back({{"name", name}, {"type", type}, {"count", values.size()}});
    const size_t bytes = values.size() * sizeof(T);
    const size_t at = body_.size();
    body_.resize(at + ((bytes + 3) & ~size_t{3}), '\0');
    if (bytes > 0) std::memcpy(body_.data() + at, values.data(), bytes);
  }
  std::string finish(json header) const {
    header["sections"] = sections_;
    std::string text = header.dump();
    text.resize((text.size() + 3) & ~size_t{3}, ' ');
    std::string out = "SVB1";
    const uint32_t n = static_cast<uint32_t>(text.size());
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((n >> (8 * i)) & 0xFF));
    out += text;
    out += body_;
    return out;
  }

 private:
  json sections_ = json::array();
  std::string body_;
};

std::string delta_frame(const Delta& d, json header) {
  Frame f;
  f.add("position_indices", d.position_indices);
  f.add("positions", d.positions);
  f.add("color_indices", d.color_indices);
  f.add("colors", d.colors);
  f.add("control", d.control_positions);
  if (d.moves) {
    f.add("moved", d.moved);
    f.add("offsets", d.offsets);
    f.add("control_moved", d.control_moved);
    f.add("control_offsets", d.control_offsets);
    header["offset_shift"] = d.offset_shift;
  }
  header["view"] = d.view_id;
  header["dense_positions"] = d.dense_positions;
  header["dense_colors"] = d.dense_colors;
  header["strokes_changed"] = d.strokes_changed;
  header["reload"] = d.reload;
  return f.finish(std::move(header));
}

// ---- request parsing -----------------------------------------------------------------------
json body_json(const httplib::Request& req) {
  json j = json::parse(req.body, nullptr, false);
  if (j.is_discarded() || !j.is_object()) {
    throw RequestError(kBadRequest, "request body is not a JSON object");
  }
  return j;
}

const json& field(const json& j, const char* key) {
  auto it = j.find(key);
  if (it == j.end()) throw RequestError(kBadRequest, std::string("missing key \"") + key + "\"");
  return *it;
}

double number(const json& j, const char* key, std::optional<double> fallback = std::nullopt) {
  if (!j.contains(key) && fallback) return *fallback;
  const json& v = field(j, key);
  if (!v.is_number() || !std::isfinite(v.get<double>())) {
    throw RequestError(kBadRequest, std::string("\"") + key + "\" must be a finite number");
  }
  return v.get<double>();
}

int64_t integer(const json& j, const char* key, std::optional<int64_t> fallback = std::nullopt) {
  if (!j.contains(key) && fallback) return *fallback;
  const json& v = field(j, key);
  if (!v.is_number_integer()) {
    throw RequestError(kBadRequest, std::string("\"") + key + "\" must be an integer");
  }
  return v.get<int64_t>();
}

int small_int(const json& j, const char* key, int fallback) {
  const int64_t v = integer(j, key, fallback);
  if (v < -1000000 || v > 1000000) {
    throw RequestError(kBadRequest, std::string("\"") + key + "\" is out of range");
  }
  return static_cast<int>(v);
}

bool flag(const json& j, const char* key, bool fallback) {
  if (!j.contains(key)) return fallback;
  const json& v = field(j, key);
  if (!v.is_boolean()) throw RequestError(kBadRequest, std::string("\"") + key + "\" must be true or false");
  return v.get<bool>();
}

std::string text(const json& j, const char* key) {
  const json& v = field(j, key);
  if (!v.is_string()) throw RequestError(kBadRequest, std::string("\"") + key + "\" must be a string");
  return v.get<std::string>();
}

subvec::Vec2 point(const json& j, const char* key) {
  const json& v = field(j, key);
  if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number() ||
      !std::isfinite(v[0].get<double>()) || !std::isfinite(v[1].get<double>())) {
    throw RequestError(kBadRequest, std::string("\"") + key + "\" must be [x, y] (finite numbers)");
  }
  return {v[0].get<double>(), v[1].get<double>()};
}

// Drags grab a vertex or a feature; color edits and Select may also take a region.
subvec::EditSelect select_mode(const json& j, bool region_too) {
  const std::string s = j.contains("select") ? text(j, "select") : "feature";
  const std::optional<subvec::EditSelect> e = subvec::edit_select_from_name(s);
  if (e && (region_too || subvec::drag_grabs(*e))) return *e;
  throw RequestError(kBadRequest, "\"select\" must be " +
                                      std::string(region_too ? subvec::kEditSelectNames
                                                             : subvec::kDragSelectNames) +
                                      ", got \"" + s + "\"");
}

// "vertices": control vertex indices, not empty (the library checks them against the level).
std::vector<int32_t> vertex_list(const json& j) {
  const json& v = field(j, "vertices");
  if (!v.is_array() || v.empty() || !std::all_of(v.begin(), v.end(), [](const json& x) {
        return x.is_number_integer() && x.get<int64_t>() >= 0 &&
               x.get<int64_t>() <= std::numeric_limits<int32_t>::max();
      })) {
    throw RequestError(kBadRequest, "\"vertices\" must be a non-empty array of vertex indices");
  }
  std::vector<int32_t> out;
  for (const json& x : v) out.push_back(static_cast<int32_t>(x.get<int64_t>()));
  return out;
}

// A color selection's radius (a region's is uncapped by default) and tolerance (regions only).
void color_reach(const json& j, subvec::EditSelect select, double& radius, double& tolerance) {
  const bool region = select == subvec::EditSelect::kRegion;
  radius = number(j, "radius", subvec::default_color_radius(select));
  if (radius < 0) throw RequestError(kBadRequest, "\"radius\" must be >= 0");
  tolerance = number(j, "tolerance", subvec::kDefaultRegionTolerance);
  if (tolerance < 0) throw RequestError(kBadRequest, "\"tolerance\" must be >= 0");
  if (!region && j.contains("tolerance")) {
    throw RequestError(kBadRequest, "\"tolerance\" applies to \"select\": \"region\" only");
  }
}

int query_int(const httplib::Request& req, const char* key, int fallback) {
  if (!req.has_param(key)) return fallback;
  const std::string v = req.get_param_value(key);
  int out = 0;
  size_t used = 0;
  try {
    out = std::stoi(v, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != v.size()) {
    throw RequestError(kBadRequest, std::string("query parameter ") + key + " must be an integer");
  }
  return out;
}

// Content types with a charset: cpp-httplib compresses only the bare "application/json",
// "image/svg+xml" and text types, and at brotli's highest effort, which took 112 s for a 33 MB SVG
// download (issue 29). Answers are small or binary; downloads compress themselves (send_download).
constexpr const char* kJson = "application/json; charset=utf-8";
constexpr const char* kSvg = "image/svg+xml; charset=utf-8";

void send_json(httplib::Response& res, const json& j, int status = 200) {
  res.status = status;
  res.set_content(j.dump(), kJson);
}

// gzip at zlib's fastest level: 30 MB of SVG in a fraction of a second, about a fifth of the bytes.
std::string gzip_fast(const std::string& in) {
  z_stream z{};
  if (deflateInit2(&z, 1, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) {
    throw std::runtime_error("zlib: deflateInit2 failed");
  }
  std::string out(deflateBound(&z, static_cast<uLong>(in.size())), '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data()));
  z.avail_in = static_cast<uInt>(in.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  const int rc = deflate(&z, Z_FINISH);
  out.resize(z.total_out);
  deflateEnd(&z);
  if (rc != Z_STREAM_END) throw std::runtime_error("zlib: deflate did not finish");
  return out;
}

// A download: text formats of 64 KiB or more go gzipped (level 1) to a client that accepts gzip;
// X-Decoded-Length gives the page the size it will receive, for its progress line.
void send_download(const httplib::Request& req, httplib::Response& res, std::string body,
                   const std::string& type) {
  const bool text = type == kJson || type == kSvg;
  res.set_header("X-Decoded-Length", std::to_string(body.size()));
  if (text && body.size() >= (64u << 10) && body.size() < (1u << 31) &&
      req.get_header_value("Accept-Encoding").find("gzip") != std::string::npos) {
    body = gzip_fast(body);
    res.set_header("Content-Encoding", "gzip");
  }
  res.set_header("Vary", "Accept-Encoding");
  res.set_content(std::move(body), type);
}

void send_error(httplib::Response& res, int status, const std::string& message) {
  send_json(res, json{{"error", message}, {"status", status}}, status);
}

bool is_loopback_host(const std::string& host) {
  return host == "127.0.0.1" || host == "localhost" || host == "::1" || host == "[::1]" ||
         host.rfind("127.", 0) == 0;
}

std::string png_bytes(const subvec::Image8& image) {
  const std::vector<uint8_t> png = subvec::encode_png(image);
  return std::string(png.begin(), png.end());
}

}  // namespace

bool looks_like_raster(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char b[12] = {};
  in.read(reinterpret_cast<char*>(b), sizeof b);
  const auto n = in.gcount();
  if (n < 4) return false;
  const bool png = b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G';
  const bool jpeg = b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF;
  const bool webp = n >= 12 && std::memcmp(b, "RIFF", 4) == 0 && std::memcmp(b + 8, "WEBP", 4) == 0;
  const bool tiff = (b[0] == 'I' && b[1] == 'I' && b[2] == 42 && b[3] == 0) ||
                    (b[0] == 'M' && b[1] == 'M' && b[2] == 0 && b[3] == 42);
  const bool bmp = b[0] == 'B' && b[1] == 'M';
  return png || jpeg || webp || tiff || bmp;
}

struct EditorServer::Impl {
  ServeOptions options;
  httplib::Server server;
  int port = 0;
  std::thread worker;  // vectorization of a raster input

  // Document state: loading until the editor exists.
  mutable std::mutex state_mutex;
  std::shared_ptr<Editor> editor;
  std::string stage = "starting";
  double fraction = 0;
  std::string failure;
  std::chrono::steady_clock::time_point started = std::chrono::steady_clock::now();
  std::atomic<bool> stopping{false};

  std::shared_ptr<Editor> ready_editor() {
    std::lock_guard lock(state_mutex);
    if (editor) return editor;
    if (!failure.empty()) throw RequestError(500, "vectorization failed: " + failure);
    throw RequestError(kUnavailable, "still vectorizing the input (" + stage + ")");
  }

  std::string name() const { return options.input.filename().string(); }
  std::string stem() const {
    std::string s = options.input.filename().string();
    for (const char* ext : {".svec.json", ".svec", ".json"}) {
      const std::string e = ext;
      if (s.size() > e.size() && s.compare(s.size() - e.size(), e.size(), e) == 0) {
        return s.substr(0, s.size() - e.size());
      }
    }
    const auto dot = s.rfind('.');
    return dot == std::string::npos || dot == 0 ? s : s.substr(0, dot);
  }

  void routes();  // the ones below
  void guards();
  void page_routes();
  void document_routes();
  void drag_routes();
  void edit_routes();
  void file_routes();
};

EditorServer::EditorServer(ServeOptions options) : impl_(std::make_unique<Impl>()) {
  impl_->options = std::move(options);
}

EditorServer::~EditorServer() {
  stop();
  if (impl_->worker.joinable()) impl_->worker.join();
}

int EditorServer::port() const { return impl_->port; }

std::string EditorServer::url() const {
  std::string host = impl_->options.host;
  if (host == "0.0.0.0" || host.empty()) host = "127.0.0.1";
  if (host.find(':') != std::string::npos) host = "[" + host + "]";
  return "http://" + host + ":" + std::to_string(impl_->port) + "/";
}

void EditorServer::stop() {
  impl_->stopping = true;
  impl_->server.stop();
}

void EditorServer::run() { impl_->server.listen_after_bind(); }

void EditorServer::start() {
  Impl& s = *impl_;
  const auto& in = s.options.input;
  if (!std::filesystem::exists(in)) throw Error(ErrorCode::kIo, in.string() + ": no such file");
  if (!std::filesystem::is_regular_file(in)) {
    throw Error(ErrorCode::kIo, in.string() + (std::filesystem::is_directory(in)
                                                   ? ": is a directory"
                                                   : ": not a regular file"));
  }
  if (s.options.output && s.options.output->has_filename()) {
    subvec::svec_format_for(*s.options.output);  // throws for an unknown extension
  }
  if (looks_like_raster(in)) {
    // Check the options and decode now, so that bad ones or a bad file fail before the server
    // starts; vectorize in the background, until done or until the server stops.
    subvec::validate(s.options.vectorize);
    auto image = std::make_shared<subvec::Image8>(subvec::read_image(in, s.options.max_pixels));
    subvec::check_vectorize_memory(image->width, image->height, s.options.vectorize);
    s.stage = "vectorizing";
    s.worker = std::thread([&s, image] {
      subvec::VectorizeOptions vo = s.options.vectorize;
      vo.cancel = &s.stopping;
      vo.progress = [&s](const std::string& stage, double fraction) {
        std::lock_guard lock(s.state_mutex);
        s.stage = stage;
        s.fraction = fraction;
      };
      try {
        auto editor = std::make_shared<Editor>(subvec::vectorize(*image, vo));
        std::lock_guard lock(s.state_mutex);
        s.editor = std::move(editor);
        s.stage = "ready";
        s.fraction = 1;
      } catch (const std::exception& e) {
        std::lock_guard lock(s.state_mutex);
        s.failure = e.what();
        s.stage = "failed";
      }
    });
  } else {
    s.editor = std::make_shared<Editor>(subvec::read_svec(in));
    s.stage = "ready";
    s.fraction = 1;
  }

  s.routes();
  // SO_REUSEADDR alone: a restarted server can bind at once, but a port another server listens
  // on is refused (cpp-httplib's default adds SO_REUSEPORT, which would let two servers share it).
  // TCP_NODELAY (inherited by the accepted sockets): an answer written in two pieces, headers and
  // body, otherwise waits for the page's delayed ACK, 40 ms on Linux, on a share of the requests.
  s.server.set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    setsockopt(sock, IPPROTO_TCP, TCP_NODELAY, &yes, sizeof yes);
  });
  s.server.set_payload_max_length(kMaxBody);
  s.server.set_read_timeout(10, 0);
  s.server.set_write_timeout(30, 0);
  if (s.options.port == 0) {
    s.port = s.server.bind_to_any_port(s.options.host);
  } else {
    s.port = s.server.bind_to_port(s.options.host, s.options.port) ? s.options.port : -1;
  }
  if (s.port <= 0) {
    throw Error(ErrorCode::kIo, "cannot listen on " + s.options.host + ":" +
                                    std::to_string(s.options.port) +
                                    " (in use, or not an address of this machine)");
  }
}

void EditorServer::Impl::routes() {
  guards();
  page_routes();
  document_routes();
  drag_routes();
  edit_routes();
  file_routes();
}

// Host and Content-Type checks before routing; errors and exceptions as JSON.
void EditorServer::Impl::guards() {
  const bool loopback = is_loopback_host(options.host);

  server.set_pre_routing_handler([loopback](const httplib::Request& req, httplib::Response& res) {
    if (loopback) {
      std::string host = req.get_header_value("Host");
      if (!host.empty() && host.front() == '[') {
        host = host.substr(0, host.find(']') + 1);
      } else {
        host = host.substr(0, host.find(':'));
      }
      if (!is_loopback_host(host)) {
        send_error(res, 403, "this server answers only requests for a loopback address");
        return httplib::Server::HandlerResponse::Handled;
      }
    }
    if (req.method == "POST" &&
        req.get_header_value("Content-Type").rfind("application/json", 0) != 0) {
      send_error(res, 415, "POST requests must have Content-Type: application/json");
      return httplib::Server::HandlerResponse::Handled;
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });

  server.set_error_handler(httplib::Server::HandlerWithResponse(
      [](const httplib::Request&, httplib::Response& res) {
        if (!res.body.empty()) return httplib::Server::HandlerResponse::Unhandled;
        std::string message = "HTTP error " + std::to_string(res.status);
        if (res.status == 400) message = "malformed request";
        if (res.status == 404) message = "no such page or API";
        if (res.status == 413) message = "request too large (at most 64 KiB)";
        if (res.status == 414) message = "request URI too long";
        send_error(res, res.status, message);
        return httplib::Server::HandlerResponse::Handled;
      }));

  server.set_exception_handler(
      [](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
        try {
          std::rethrow_exception(ep);
        } catch (const RequestError& e) {
          send_error(res, e.status(), e.what());
        } catch (const Error& e) {
          send_error(res, e.code() == ErrorCode::kInvalidArgument ? kUnprocessable : 500, e.what());
        } catch (const std::bad_alloc&) {
          send_error(res, 500, "out of memory");
        } catch (const std::exception& e) {
          send_error(res, 500, e.what());
        } catch (...) {
          send_error(res, 500, "unknown error");
        }
      });
}

// The editor page (web/dist, embedded).
void EditorServer::Impl::page_routes() {
  // ---- the page ----
  auto serve_asset = [](const std::string& path, httplib::Response& res) {
    const EmbeddedAsset* asset = find_asset(path);
    if (!asset) throw RequestError(kNotFound, "no such file: " + path);
    res.set_content(reinterpret_cast<const char*>(asset->data), asset->size, asset->content_type);
    res.set_header("Cache-Control", "no-cache");
  };
  server.Get("/", [serve_asset](const httplib::Request&, httplib::Response& res) {
    serve_asset("index.html", res);
  });
  server.Get("/assets/(.+)", [serve_asset](const httplib::Request& req, httplib::Response& res) {
    serve_asset("assets/" + req.matches[1].str(), res);
  });
}

// The document: loading state, levels, sessions and the meshes the page draws.
void EditorServer::Impl::document_routes() {
  // ---- state ----
  server.Get("/api/status", [this](const httplib::Request&, httplib::Response& res) {
    std::lock_guard lock(state_mutex);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    json j = {{"name", name()},
              {"state", editor ? "ready" : !failure.empty() ? "failed" : "vectorizing"},
              {"stage", stage},
              {"fraction", fraction},
              {"seconds", seconds},
              {"version", editor ? editor->version() : 0}};
    if (!failure.empty()) j["error"] = failure;
    send_json(res, j);
  });

  // ?session=: undo and redo count that session's tab's steps.
  server.Get("/api/document", [this](const httplib::Request& req, httplib::Response& res) {
    const DocumentInfo info =
        ready_editor()->info(req.has_param("session") ? req.get_param_value("session") : "");
    json levels = json::array();
    for (const auto& l : info.levels) {
      levels.push_back({{"vertices", l.vertices},
                        {"triangles", l.triangles},
                        {"colors", l.colors},
                        {"features", l.features},
                        {"mean_edge", l.mean_edge}});
    }
    json objects = json::array();
    for (const auto& o : info.objects) {
      objects.push_back({{"level", o.level}, {"name", o.name}, {"visible", o.visible}, {"vertices", o.vertices},
                         {"strokes", o.strokes}});
    }
    json save = nullptr;
    if (options.output) save = options.output->string();
    send_json(res, {{"name", name()},
                    {"stem", stem()},
                    {"version", info.version},
                    {"width", info.width},
                    {"height", info.height},
                    {"levels", levels},
                    {"objects", objects},
                    {"undo", info.undo},
                    {"redo", info.redo},
                    {"strokes", info.strokes},
                    {"save_to", save},
                    {"filter",
                     {{"available", info.bands > 0},
                      {"bands", info.bands},
                      {"current", info.filter ? json{{"eta", info.filter->eta},
                                                     {"geometry", info.filter->geometry},
                                                     {"color", info.filter->color}}
                                              : json(nullptr)},
                      {"reason", info.bands > 0 ? ""
                                                : "this image has one level, so no pyramid to filter "
                                                  "(vectorize it with --levels 2 or more)"}}}});
  });

  // {tab?}: the page's id for its browser tab (kept across reloads), whose edits its undo takes
  // back: 1 to 64 letters, digits and dashes.
  server.Post("/api/session", [this](const httplib::Request& req, httplib::Response& res) {
    const json j = body_json(req);
    std::string tab;
    if (j.contains("tab")) {
      tab = text(j, "tab");
      const bool ok = !tab.empty() && tab.size() <= 64 &&
                      std::all_of(tab.begin(), tab.end(), [](char c) {
                        return std::isalnum(static_cast<unsigned char>(c)) || c == '-';
                      });
      if (!ok) throw RequestError(kBadRequest, "\"tab\" must be 1 to 64 letters, digits or dashes");
    }
    send_json(res, {{"session", ready_editor()->new_session(tab)}});
  });

  server.Get("/api/control", [this](const httplib::Request& req, httplib::Response& res) {
    const Editor::ControlData c = ready_editor()->control(query_int(req, "level", 0));
    send_json(res, {{"positions", c.positions}, {"edges", c.edges}, {"features", c.features}});
  });

  server.Get("/api/strokes", [this](const httplib::Request& req, httplib::Response& res) {
    json out = json::array();
    for (const StrokeGeometry& s : ready_editor()->strokes(query_int(req, "level", 0))) {
      out.push_back({{"points", s.points},
                     {"half_widths", s.half_widths},
                     {"color", {s.color.r, s.color.g, s.color.b}}});
    }
    send_json(res, out);
  });

  server.Post("/api/view", [this](const httplib::Request& req, httplib::Response& res) {
    const json j = body_json(req);
    ViewRequest v;
    v.level = small_int(j, "level", v.level);
    v.depth = small_int(j, "depth", v.depth);
    v.scale = number(j, "scale", v.scale);
    v.max_edge_pixels = number(j, "max_edge_pixels", v.max_edge_pixels);
    v.have = integer(j, "have", v.have);
    if (j.contains("window") && !j["window"].is_null()) {
      const json& w = j["window"];
      if (!w.is_array() || w.size() != 4 ||
          !std::all_of(w.begin(), w.end(), [](const json& x) {
            return x.is_number() && std::isfinite(x.get<double>());
          })) {
        throw RequestError(kBadRequest, "\"window\" must be [x0, y0, x1, y1] (finite numbers)");
      }
      v.x0 = w[0].get<double>();
      v.y0 = w[1].get<double>();
      v.x1 = w[2].get<double>();
      v.y1 = w[3].get<double>();
    }
    std::shared_ptr<Editor> doc = ready_editor();
    const ViewMesh m = doc->view(text(j, "session"), v);
    Frame f;
    f.add("positions", m.positions);
    f.add("colors", m.colors);
    f.add("triangles", m.triangles);
    f.add("coarse_triangles", m.coarse_triangles);
    f.add("tear_lines", m.tear_lines);
    f.add("object_positions", m.object_positions);
    f.add("object_colors", m.object_colors);
    json objects = json::array();
    for (const ViewMesh::ObjectRange& o : m.objects) {
      objects.push_back({{"object", o.object}, {"first", o.first}, {"count", o.count}});
    }
    const std::string body = f.finish({{"view", m.id},
                                       {"objects", objects},
                                       {"level", m.level},
                                       {"depth", m.depth},
                                       {"partial", m.partial},
                                       {"unchanged", m.unchanged},
                                       {"version", doc->version()}});
    res.set_content(body, "application/octet-stream");
  });
}

// Picking and dragging (drag and move-feature tools).
void EditorServer::Impl::drag_routes() {
  server.Post("/api/select", [this](const httplib::Request& req, httplib::Response& res) {
    const json j = body_json(req);
    SelectRequest s;
    s.level = small_int(j, "level", 0);
    s.select = select_mode(j, true);
    if (s.select == subvec::EditSelect::kVertices) {
      throw RequestError(kBadRequest, "\"select\": \"vertices\" is for color edits");
    }
    s.at = point(j, "at");
    color_reach(j, s.select, s.radius, s.tolerance);
    const SelectResult r = ready_editor()->select(s);
    send_json(res, {{"vertex", r.vertex},
                    {"feature", r.feature},
                    {"distance", r.distance},
                    {"chain", r.chain},
                    {"region", r.region},
                    {"colors", r.colors}});
  });

  server.Post("/api/drag/start", [this](const httplib::Request& req, httplib::Response& res) {
    const json j = body_json(req);
    DragStart d;
    d.level = small_int(j, "level", 0);
    const std::string tool = j.contains("tool") ? text(j, "tool") : "drag";
    if (tool != "drag" && tool != "move" && tool != "points") {
      throw RequestError(kBadRequest, "\"tool\" must be \"drag\", \"move\" or \"points\"");
    }
    d.move_feature = tool == "move";
    if (tool == "points") d.vertices = vertex_list(j);  // the selection moves
    d.select = select_mode(j, false);
    d.at = point(j, "at");
    // A number, or "auto": the editor picks an extent local to what is grabbed.
    const auto extent = [&](const char* key, double fallback, bool& is_auto) {
      is_auto = j.contains(key) && j[key] == "auto";
      return is_auto ? fallback : number(j, key, fallback);
    };
    d.sigma = extent("sigma", 20.0, d.auto_sigma);
    d.region = extent("region", 0.0, d.auto_region);
    const SelectResult r =
        ready_editor()->drag_start(text(j, "session"), integer(j, "version"), d);
    send_json(res, {{"vertex", r.vertex}, {"feature", r.feature}, {"chain", r.chain},
                    {"sigma", r.drag_sigma}, {"region", r.drag_region}});
  });

  server.Post("/api/drag/move", [this](const httplib::Request& req, httplib::Response& res) {
    const json j = body_json(req);
    const Delta d =
        ready_editor()->drag_move(text(j, "session"), point(j, "to"), number(j, "rotate", 0.0));
    res.set_content(delta_frame(d, {{"preview", true}}), "application/octet-stream");
  });

  server.Post("/api/drag/end", [this](const httplib::Request& req, httplib::Response& res) {
    const json j = body_json(req);
    std::shared_ptr<Editor> doc = ready_editor();
    std::string log;
    const Delta d = doc->drag_end(text(j, "session"), integer(j, "version"), point(j, "to"),
                                     number(j, "rotate", 0.0), log);
    res.set_content(delta_frame(d, {{"version", doc->version()}, {"log", log}}),
                    "application/octet-stream");
  });

  server.Post("/api/drag/cancel", [this](const httplib::Request& req, httplib::Response& res) {
    const json j = body_json(req);
    ready_editor()->drag_cancel(text(j, "session"));
    send_json(res, {{"ok", true}});
  });
}

// Edits that apply at once: color, stylize, undo / redo, the pyramid filter.
void EditorServer::Impl::edit_routes() {
  server.Post("/api/color", [this](const httplib::Request& req, httplib::Response& res) {
    const json j = body_json(req);
    subvec::EditOp op;
    op.kind = subvec::EditOp::Kind::kColor;
    op.level = small_int(j, "level", 0);
    op.select = select_mode(j, true);
    if (op.select == subvec::EditSelect::kVertices) {
      op.vertices = vertex_list(j);
    } else {
      op.at = point(j, "at");
      color_reach(j, op.select, op.radius, op.tolerance);
    }
    const std::string mode = j.contains("mode") ? text(j, "mode") : "blend";
    if (mode != "blend" && mode != "transform") {
      throw RequestError(kBadRequest, "\"mode\" must be \"blend\" or \"transform\"");
    }
    op.mode = mode == "blend" ? subvec::ColorMode::kBlend : subvec::ColorMode::kTransform;
    const json& c = field(j, "color");
    if (!c.is_array() || c.size() != 3 || !std::all_of(c.begin(), c.end(), [](const json& x) {
          return x.is_number() && x.get<double>() >= 0 && x.get<double>() <= 255;
        })) {
      throw RequestError(kBadRequest, "\"color\" must be [r, g, b] with values 0 to 255");
    }
    op.color = {c[0].get<float>(), c[1].get<float>(), c[2].get<float>()};
    op.amount = number(j, "amount", 0.5);
    std::shared_ptr<Editor> doc = ready_editor();
    std::string log;
    const Delta d = doc->apply(text(j, "session"), integer(j, "version"), op, log);
    res.set_content(delta_frame(d, {{"version", doc->version()}, {"log", log}}),
                    "application/octet-stream");
  });

  // The pen tool: a new feature along the drawn points; and a feature deleted (issue 25).
  server.Post("/api/feature/add", [this](const httplib::Request& req, httplib::Response& res) {
    const json j = body_json(req);
    subvec::EditOp op;
    op.kind = subvec::EditOp::Kind::kAddFeature;
    op.level = small_int(j, "level", 0);
    const json& points = field(j, "points");
    if (!points.is_array() || points.size() < 2 || points.size() > 100000) {
      throw RequestError(kBadRequest, "\"points\" must be an array of 2 to 100000 points [x, y]");
    }
    for (const json& p : points) {
      if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number()) {
        throw RequestError(kBadRequest, "\"points\" must hold points [x, y]");
      }
      op.points.push_back({p[0].get<double>(), p[1].get<double>()});
    }
    const std::string kind = j.contains("kind") ? text(j, "kind") : "tear";
    if (kind != "tear" && kind != "crease") throw RequestError(kBadRequest, "\"kind\" must be \"tear\" or \"crease\"");
    op.feature_kind = kind == "tear" ? subvec::FeatureKind::kTear : subvec::FeatureKind::kCrease;
    std::shared_ptr<Editor> doc = ready_editor();
    std::string log;
    const Delta d = doc->apply(text(j, "session"), integer(j, "version"), op, log);
    res.set_content(delta_frame(d, {{"version", doc->version()}, {"log", log}}),
                    "application/octet-stream");
  });
  server.Post("/api/feature/delete", [this](const httplib::Request& req, httplib::Response& res) {
    const json j = body_json(req);
    subvec::EditOp op;
    op.kind = subvec::EditOp::Kind::kDeleteFeature;
    op.level = small_int(j, "level", 0);
    op.at = point(j, "at");
    std::shared_ptr<Editor> doc = ready_editor();
    std::string log;
    const Delta d = doc->apply(text(j, "session"), integer(j, "version"), op, log);
    res.set_content(delta_frame(d, {{"version", doc->version()}, {"log", log}}),
                    "application/octet-stream");
  });

  // Objects (edit/objects.h, issue 26): made from a rectangle (or a click inside a closed feature),
  // moved, hidden or shown, reordered. Each is one edit; the page's view reloads.
  const auto object_edit = [this](httplib::Response& res, subvec::EditOp op, const json& j) {
    op.level = small_int(j, "level", 0);
    std::shared_ptr<Editor> doc = ready_editor();
    std::string log;
    const Delta d = doc->apply(text(j, "session"), integer(j, "version"), op, log);
    res.set_content(delta_frame(d, {{"version", doc->version()}, {"log", log}}), "application/octet-stream");
  };
  const auto object_index = [](const json& j, const char* key) {
    const int64_t o = integer(j, key, -1);
    if (o < 0 || o >= subvec::Limits::kMaxObjects) {
      throw RequestError(kBadRequest, std::string("\"") + key + "\" must be an object index, 0 to " +
                                          std::to_string(subvec::Limits::kMaxObjects - 1));
    }
    return static_cast<int>(o);
  };
  server.Post("/api/object/make", [this, object_edit](const httplib::Request& req, httplib::Response& res) {
    const json j = body_json(req);
    subvec::EditOp op;
    op.kind = subvec::EditOp::Kind::kMakeObject;
    if (j.contains("rect")) {
      const json& r = j["rect"];
      if (!r.is_array() || r.size() != 4 || !std::all_of(r.begin(), r.end(), [](const json& x) {
            return x.is_number_integer() && x.get<int64_t>() >= 0 && x.get<int64_t>() <= subvec::Limits::kMaxDimension;
          })) {
        throw RequestError(kBadRequest, "\"rect\" must be [x, y, width, height] (whole pixels >= 0)");
      }
      op.rect = std::array<int, 4>{r[0].get<int>(), r[1].get<int>(), r[2].get<int>(), r[3].get<int>()};
    } else {
      op.at = point(j, "at");
    }
    if (j.contains("name")) op.object_name = text(j, "name");
    object_edit(res, op, j);
  });
  server.Post("/api/object/move", [this, object_edit, object_index](const httplib::Request& req, httplib::Response& res) {
    const json j = body_json(req);
    subvec::EditOp op;
    op.kind = subvec::EditOp::Kind::kMoveObject;
    op.object = object_index(j, "object");
    op.translate = j.contains("translate") ? point(j, "translate") : Vec2{};
    op.rotate = number(j, "rotate", 0.0);
    op.scale = number(j, "scale", 1.0);
    if (!(op.scale > 0)) throw RequestError(kBadRequest, "\"scale\" must be a positive number");
    if (j.contains("pivot")) op.pivot = point(j, "pivot");
    object_edit(res, op, j);
  });
  server.Post("/api/object/visible", [this, object_edit, object_index](const httplib::Request& req, httplib::Response& res) {
    const json j = body_json(req);
    subvec::EditOp op;
    op.object = object_index(j, "object");
    const json& visible = field(j, "visible");
    if (!visible.is_boolean()) throw RequestError(kBadRequest, "\"visible\" must be true or false");
    op.kind = visible.get<bool>() ? subvec::EditOp::Kind::kShowObject : subvec::EditOp::Kind::kHideObject;
    object_edit(res, op, j);
  });
  server.Post("/api/object/order", [this, object_edit, object_index](const httplib::Request& req, httplib::Response& res) {
    const json j = body_json(req);
    subvec::EditOp op;
    op.kind = subvec::EditOp::Kind::kOrderObject;
    op.object = object_index(j, "object");
    op.position = object_index(j, "to");
    object_edit(res, op, j);
  });

  // A nudge of the points tool's selection (the arrow keys): a move of control vertices.
  server.Post("/api/points/move", [this](const httplib::Request& req, httplib::Response& res) {
    const json j = body_json(req);
    subvec::EditOp op;
    op.kind = subvec::EditOp::Kind::kMoveVertices;
    op.level = small_int(j, "level", 0);
    op.vertices = vertex_list(j);
    op.translate = point(j, "translate");
    std::shared_ptr<Editor> doc = ready_editor();
    // A number, or "auto": local to the selection (subvec::suggested_drag_extent).
    op.region = j.contains("region") && j["region"] == "auto"
                    ? doc->suggested_region(op.level, op.vertices)
                    : number(j, "region", 0.0);
    if (op.region < 0) throw RequestError(kBadRequest, "\"region\" must be >= 0");
    std::string log;
    const Delta d = doc->apply(text(j, "session"), integer(j, "version"), op, log);
    res.set_content(delta_frame(d, {{"version", doc->version()}, {"log", log}}),
                    "application/octet-stream");
  });

  server.Post("/api/stylize", [this](const httplib::Request& req, httplib::Response& res) {
    const json j = body_json(req);
    std::optional<double> threshold;
    if (j.contains("threshold") && !j["threshold"].is_null()) threshold = number(j, "threshold");
    const int64_t seed = integer(j, "seed", 1);
    if (seed < 0) throw RequestError(kBadRequest, "\"seed\" must be >= 0");
    std::shared_ptr<Editor> doc = ready_editor();
    std::string log;
    std::optional<int> object;
    if (j.contains("object") && !j["object"].is_null()) object = small_int(j, "object", 0);
    const Delta d = doc->stylize(text(j, "session"), integer(j, "version"),
                                    small_int(j, "level", 0), object, threshold,
                                    static_cast<uint64_t>(seed), number(j, "probability", 0.3), log);
    res.set_content(delta_frame(d, {{"version", doc->version()}, {"log", log}}),
                    "application/octet-stream");
  });

  auto history = [this](bool undo) {
    return [this, undo](const httplib::Request& req, httplib::Response& res) {
      const json j = body_json(req);
      std::shared_ptr<Editor> doc = ready_editor();
      std::string label;
      const Delta d = undo ? doc->undo(text(j, "session"), integer(j, "version"), label)
                           : doc->redo(text(j, "session"), integer(j, "version"), label);
      res.set_content(delta_frame(d, {{"version", doc->version()}, {"log", label}}),
                      "application/octet-stream");
    };
  };
  server.Post("/api/undo", history(true));
  server.Post("/api/redo", history(false));

  // Filtering of the pyramid's detail bands (paper §6.4), through subvec::filter as `subvec filter`.
  server.Post("/api/filter", [this](const httplib::Request& req, httplib::Response& res) {
    const json j = body_json(req);
    FilterRequest request;
    const json& eta = field(j, "eta");
    if (!eta.is_array() || eta.size() > 64) {
      throw RequestError(kBadRequest, "\"eta\" must be an array of numbers, one per band");
    }
    for (const json& v : eta) {
      if (!v.is_number()) throw RequestError(kBadRequest, "\"eta\" must hold numbers");
      request.eta.push_back(v.get<double>());
    }
    request.geometry = flag(j, "geometry", false);
    request.color = flag(j, "color", true);
    if (j.contains("object") && !j["object"].is_null()) request.object = small_int(j, "object", 0);
    std::shared_ptr<Editor> doc = ready_editor();
    std::string log;
    const Delta d = doc->filter(text(j, "session"), integer(j, "version"), request, log);
    res.set_content(delta_frame(d, {{"version", doc->version()}, {"log", log}}),
                    "application/octet-stream");
  });
}

// Saving in place and downloads.
void EditorServer::Impl::file_routes() {
  server.Post("/api/save", [this](const httplib::Request& req, httplib::Response& res) {
    const json j = body_json(req);
    std::shared_ptr<Editor> doc = ready_editor();
    if (!options.output) {
      throw RequestError(kConflict, "no output file was named (start with -o OUT.svec to save in "
                                    "place; Download works without it)");
    }
    auto [image, version] = doc->snapshot();
    if (j.contains("version") && integer(j, "version") != version) {
      throw RequestError(kConflict, "the document changed in another tab (now version " +
                                        std::to_string(version) + "): reloaded, save again");
    }
    subvec::write_svec(*options.output, image);
    send_json(res, {{"saved", options.output->string()}, {"version", version}});
  });

  server.Get("/api/download", [this](const httplib::Request& req, httplib::Response& res) {
    const std::string format = req.has_param("format") ? req.get_param_value("format") : "svec";
    auto [image, version] = ready_editor()->snapshot();
    const int level = query_int(req, "level", 0);
    if (level < 0 || level >= static_cast<int>(image.levels.size())) {
      throw RequestError(kBadRequest, "level " + std::to_string(level) + " is out of range");
    }
    std::string body, type, ext = format;
    if (format == "svec") {
      const std::vector<uint8_t> bytes = subvec::to_svec_binary(image);
      body.assign(bytes.begin(), bytes.end());
      type = "application/octet-stream";
    } else if (format == "svec.json") {
      body = subvec::to_svec_json(image);
      type = kJson;
    } else if (format == "png") {
      subvec::RenderOptions ro;
      ro.level = level;
      body = png_bytes(subvec::render(image, ro));
      type = "image/png";
    } else if (format == "pdf" || format == "svg") {
      subvec::ExportOptions eo;
      eo.level = level;
      body = format == "pdf" ? subvec::to_pdf(image, eo) : subvec::to_svg(image, eo);
      type = format == "pdf" ? "application/pdf" : kSvg;
    } else {
      throw RequestError(kBadRequest, "unknown format '" + format +
                                          "' (expected svec, svec.json, png, pdf or svg)");
    }
    std::string file = stem();
    for (char& ch : file) {
      if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '-' && ch != '_' && ch != '.') ch = '_';
    }
    res.set_header("Content-Disposition",
                   "attachment; filename=\"" + file + "-v" + std::to_string(version) + "." +
                       ext + "\"");
    send_download(req, res, std::move(body), type);
  });
}

}  // namespace subvec_serve
