// The viewer's WebAssembly (web/viewer/wasm, docs/viewer.md "Why WebAssembly"): built with
// Debian's clang and lld, no C library (wasm/build). Memory is one arena: JavaScript resets it,
// copies a call's inputs in, calls, and copies the outputs out (src/wasm.ts).
#pragma once
#include <stddef.h>
#include <stdint.h>

#ifdef __wasm__
#define EXPORT(name) __attribute__((export_name(#name)))
#define IMPORT(name) __attribute__((import_module("env"), import_name(#name)))
#else // fuzz/viewer_decode_fuzz.cpp builds the decoder natively, with its own alloc and imports
#define EXPORT(name)
#define IMPORT(name)
#endif

// n bytes, 8-aligned, zeroed; 0 when memory cannot grow.
void *alloc(size_t n);
// count elements of `size` bytes (count in 64 bits, so that no product wraps); 0 when they do not fit.
void *alloc_array(size_t size, double count);

#define NEW(type, count) ((type *)alloc_array(sizeof(type), (double)(count)))
#define CHECK(p) \
  if (!(p)) return 0
