// The viewer's WebAssembly (web/viewer/wasm, docs/viewer.md "Why WebAssembly"): built with
// Debian's clang and lld, no C library (wasm/build). Memory is one arena: JavaScript resets it,
// copies a call's inputs in, calls, and copies the outputs out (src/wasm.ts).
#pragma once
#include <stddef.h>
#include <stdint.h>

#define EXPORT(name) __attribute__((export_name(#name)))
#define IMPORT(name) __attribute__((import_module("env"), import_name(#name)))

// n bytes, 8-aligned, zeroed; 0 when memory cannot grow.
void *alloc(size_t n);

#define NEW(type, count) ((type *)alloc(sizeof(type) * (size_t)(count)))
#define CHECK(p) \
  if (!(p)) return 0
