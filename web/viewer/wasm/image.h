// The image as the file readers (json.c) leave it in the module's memory: what validate.c checks
// and what JavaScript reads back (src/wasm.ts, image()). 32-bit fields; an Array is a count, then
// a pointer.
#pragma once
#include "memory.h"

typedef struct { int32_t n; void *data; } Array; // n values

typedef struct {
  Array positions, colors, triangles, triangle_colors, creases, parents, collapses;
  int32_t num_features;
  int32_t *feature_ids;
  double *saliency;
  Array *feature_vertices;
  const void *edges; // a compact level: the edges decode.c built (its Edges), which check_level trusts; else 0
} JsonLevel;
typedef struct { int32_t level; float width, color[3], taper; Array points; } JsonStroke;
typedef struct { int32_t n; JsonStroke *items; } Strokes;
typedef struct { const uint8_t *key; int32_t keyn; const uint8_t *value; int32_t valuen; } JsonEntry;
typedef struct { int32_t level, visible; const uint8_t *name; int32_t namen; JsonLevel mesh; Strokes strokes; } JsonObject;
typedef struct {
  int32_t width, height, num_levels;
  JsonLevel *levels;
  Strokes strokes;
  int32_t num_metadata;
  JsonEntry *metadata;
  int32_t num_objects;
  JsonObject *objects;
} JsonImage;

// docs/format.md's rules that span the image (validate() of src/mesh/validate.cpp), each level's
// and each object's mesh by decode.c's check_level and check_object: SvecError on the first broken.
void validate_image(const JsonImage *image);
