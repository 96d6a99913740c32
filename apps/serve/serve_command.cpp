// `subvec serve IN [-o OUT] [--port P] [--host H]`: the options, the banner, and a clean stop on
// Ctrl+C (SIGINT) or SIGTERM through a thread that waits for the signal.
#include "serve_command.h"

#include <csignal>
#include <cstdlib>
#include <iostream>
#include <pthread.h>
#include <thread>

#include "server.h"
#include "subvec/core/error.h"
#include "vectorize_options.h"

namespace subvec_serve {

namespace {

void run_serve(ServeOptions& options, const subvec_cli::VectorizeParams& params) {
  // The library's ranges, as usage errors (as `subvec vectorize` reports them).
  options.vectorize = subvec_cli::vectorize_options(params);
  // Block the stop signals in every thread (the server's pool inherits the mask) and wait for
  // them in one thread, which stops the server: no work in a signal handler.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  EditorServer server(options);
  try {
    server.start();
  } catch (const subvec::Error& e) {
    // The memory check of a raster input, named after its flag as `subvec vectorize` names it.
    if (e.code() != subvec::ErrorCode::kLimit) throw;
    throw subvec::Error(e.code(), subvec_cli::with_flag_names(e.what()));
  }
  std::cout << "subvec: editing " << options.input.string() << " at " << server.url()
            << "  (Ctrl+C stops)" << std::endl;
  std::thread waiter([&server, signals] {
    int received = 0;
    sigwait(&signals, &received);
    server.stop();
  });
  server.run();
  // run() also returns when listening fails; wake the waiter either way.
  pthread_kill(waiter.native_handle(), SIGTERM);
  waiter.join();
  // Nothing is left to write (Save writes synchronously and atomically); leave without waiting
  // for a vectorization still running in the background.
  std::cout.flush();
  std::_Exit(0);
}

}  // namespace

void add_serve_command(CLI::App& app) {
  static ServeOptions options;  // live until the callback has run
  static subvec_cli::VectorizeParams params;
  CLI::App* serve = app.add_subcommand(
      "serve", "Edit a vector image (or a photograph, vectorized first) in the browser");
  serve->add_option("input", options.input, "Vector image (.svec, .svec.json) or raster image")
      ->required();
  serve->add_option("-o,--output", options.output,
                    "Where Save writes (.svec or .svec.json); without it, Save downloads")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            const bool ok = text.ends_with(".svec") || text.ends_with(".svec.json") ||
                            text.ends_with(".json");
            return ok ? std::string() : "expected a .svec or .svec.json path, got '" + text + "'";
          },
          "OUT", "svec path"));
  serve->add_option("--port", options.port, "TCP port (default 8080; 0: any free port)")
      ->check(CLI::Range(0, 65535));
  serve->add_option("--host", options.host,
                    "Address to listen on (default 127.0.0.1: this machine only)");
  // A raster input is vectorized as `subvec vectorize` does it, with the same options.
  subvec_cli::add_vectorize_options(serve, params);
  subvec_cli::add_limit_options(serve, params, options.max_pixels);  // for a raster input
  serve->footer(
      "Examples:\n"
      "  subvec serve examples/01-disk.svec.json              # then open the printed URL\n"
      "  subvec serve photo.png --vertices 3000               # vectorized first, progress in the page\n"
      "  subvec serve in.svec -o edited.svec --port 0         # Save writes edited.svec; any free port");
  serve->callback([] { run_serve(options, params); });
}

}  // namespace subvec_serve
