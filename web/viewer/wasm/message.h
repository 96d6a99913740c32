// The messages of the viewer's WebAssembly: each problem is one line, the C++ reader's, built
// here and thrown by the imported fail() as a SvecError (src/wasm.ts). Numbers go into the text
// as a marker byte (0xfd to 0xff, which UTF-8 never uses) and the double's 8 bytes; JavaScript
// writes them as String(v), printf's "%g" or nlohmann's dump() do, since those need decimal
// conversions that are JavaScript's own.
#pragma once
#include "memory.h"

enum { AS_INTEGER = 0xfd, AS_G, AS_DUMP };

// The level the messages name ("level L ", and "level L: " while `message_prefix` is 1, "object
// L: " while it is 2), and its positions (for the messages that show a vertex's position).
// "object N stroke K: " / "stroke K: " while it is 3, with message_owner N (-1: the image's) and
// message_level K.
extern int32_t message_level, message_prefix, message_owner;
extern const double *message_positions;

void say_start(void);
void say(const char *text);
void say_bytes(const uint8_t *bytes, int32_t n);
void say_number(int as, double v);
__attribute__((noreturn)) void say_fail(void);

// The message of `code` (the templates of message.c, in this order) with up to seven numbers.
__attribute__((noreturn)) void fail_code(int32_t code, double a, double b, double c, double d, double e, double f, double g);
#define FAIL(...) FAIL_(__VA_ARGS__, 0, 0, 0, 0, 0, 0, 0, 0)
#define FAIL_(code, a, b, c, d, e, f, g, ...) fail_code(code, a, b, c, d, e, f, g)

enum {
  E_OUT_OF_MEMORY,
  // range-coded stream (version 3)
  E_FIRST_BYTES, E_ENDS_EARLY, E_WIDE_NUMBER, E_TRAILING_STREAM, E_LEAVES_INTERVAL,
  // varint sections (version 2)
  E_TRUNCATED, E_MALFORMED_VARINT, E_OPERATION_BYTE, E_TRAILING_SECTION, E_SALIENCY_TAG, E_FEW_STEP_BYTES,
  // connectivity
  E_VIRTUAL, E_ENDS_BEFORE, E_OUTRUN, E_MORE_VERTICES, E_CLOSES_LOOP, E_LOOP_OF_3, E_SPLIT_OFFSET, E_DEGENERATE,
  E_UNVISITED, E_VERTEX_COUNT, E_TRIANGLE_COUNT,
  // positions, creases and features
  E_POSITION_RESIDUAL, E_VERTEX_RANGE, E_STEP_RANGE, E_FEATURE_ID, E_FEATURE_LENGTH,
  // topology (as MeshTopology::build words them)
  E_TRIANGLE_VERTEX, E_REPEATS_VERTEX, E_SHARED_EDGE, E_ORIENTATION, E_MARK_RANGE, E_NOT_AN_EDGE, E_ON_BORDER,
  E_ALREADY_CREASE, E_ALREADY_TEAR, E_SHORT_FEATURE,
  // colors
  E_COLOR_COUNT, E_COLOR_RESIDUAL, E_COLOR_VALUE,
  // a level's validity rules (check_level)
  V_POSITION_NOT_FINITE, V_POSITION_OUTSIDE, V_COLOR_NOT_FINITE, V_TRIANGLE_COLOR, V_REPEATED_ID, V_SALIENCY,
  V_FLIPPED, V_UNUSED_VERTEX, V_GAP_EDGE, V_NO_CORNER, V_ANGLES, V_AREA, V_COLOR_OWNER, V_UNUSED_COLOR, V_COLOR_EDGE,
  // an object's mesh (check_object)
  V_POSITION_FAR, V_NO_TRIANGLES, V_BOUNDARY_EDGES, V_TURNS,
  // the image-wide rules (validate.c): size, pyramid links, objects, strokes
  V_NOT_POSITIVE, V_OVER_LIMIT, V_IMAGE_SIZE, V_NO_LEVELS,
  L_LEVEL_0, L_PARENT_COUNT, L_COLLAPSE_COUNT, L_PARENT_RANGE, L_PARENT_TWICE, L_COLLAPSE_RANGE, L_COLLAPSE_REMOVES,
  O_LEVEL, O_NAME, O_RECORD, O_STROKE_LEVEL, S_FEW_POINTS, S_POINT, S_WIDTH, S_COLOR, S_TAPER,
};
// Words of the templates' \5 (section names first, in decode.c's order).
enum { W_OVERLAP = 7, W_GAP, W_CORNER, W_WIDTH = 12 };
