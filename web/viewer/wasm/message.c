#include "message.h"

IMPORT(fail) __attribute__((noreturn)) void js_fail(const uint8_t *message, int32_t n);

int32_t message_level, message_prefix, message_owner;
const double *message_positions;

static uint8_t *text;
static int32_t said, room;

void say_start(void) { said = room = 0; }

void say_bytes(const uint8_t *bytes, int32_t n) {
  if (said + n > room) {
    int32_t grown = 2 * (said + n) + 256;
    uint8_t *to = (uint8_t *)alloc((size_t)grown);
    if (!to) js_fail((const uint8_t *)"out of memory: the image needs more than WebAssembly can hold", 61);
    if (said) __builtin_memcpy(to, text, (size_t)said);
    text = to, room = grown;
  }
  __builtin_memcpy(text + said, bytes, (size_t)n);
  said += n;
}
void say(const char *s) {
  int32_t n = 0;
  while (s[n]) ++n;
  say_bytes((const uint8_t *)s, n);
}
void say_number(int as, double v) {
  uint8_t marker = (uint8_t)as;
  say_bytes(&marker, 1);
  say_bytes((const uint8_t *)&v, 8);
}
void say_fail(void) { js_fail(text, said); }

// The templates: text, and directives that take the next numbers: \3 an integer, \4 a number as
// "%g", \5 a word, \6 chain (is feature, i): "feature i" or "crease i", \7 the same with the id
// ("feature i (id d)"), \10 a vertex's position "(x, y)", \16 what a version 2 section read
// (section, feature: the section's name, or "feature i" when i >= 0). \1 is the level's name
// ("level L "), \2 the checks' prefix ("level L: ", "object L: ", or a stroke's "stroke L: " or
// "object N stroke L: ").
static const char *const TEMPLATES[] = {
  "out of memory: the image needs more than WebAssembly can hold",
  "\1stream: corrupt coded data (bad first bytes)",
  "\1stream \5: the coded data ends early (\3 bytes)",
  "\1stream \5: a number of more than 56 bits",
  "\3 unexpected bytes at the end of \1stream",
  "\1stream: corrupt coded data (the code leaves its interval)",
  "truncated payload while reading \1\16 (needs \3 bytes at offset \3, \3 left)",
  "malformed varint while reading \1\16",
  "\1connectivity: byte \3 is not three operations",
  "\3 unexpected bytes at the end of \1\5",
  "\1feature \3: unknown saliency tag \3",
  "\1feature \3: \3 vertices, too few bytes",
  "\1connectivity: virtual vertex \3 out of range",
  "\1connectivity: the traversal ends before the last operation",
  "\1connectivity: the operations outrun the stream",
  "\1connectivity: more vertices than the \3 declared",
  "\1connectivity: operation \3 closes a loop of \3 edges",
  "\1connectivity: operation \3 on a loop of 3 edges",
  "\1connectivity: split offset out of range",
  "\1connectivity: operation \3 makes a degenerate triangle",
  "\1connectivity: the traversal leaves triangles unvisited",
  "\1connectivity: \3 vertices, but \3 are declared",
  "\1connectivity: \3 triangles, but \3 are declared",
  "\1positions: residual out of range",
  "\1\6: vertex \3 out of range",
  "\1\6: step \3 out of range",
  "\1feature \3: id out of range",
  "\1feature \3: \3 vertices, more than the level has",
  "\2triangle \3 refers to vertex \3, out of range (\3 vertices)",
  "\2triangle \3 repeats vertex \3",
  "\2edge (\3, \3) is shared by more than two triangles",
  "\2triangles \3 and \3 are oriented inconsistently across edge (\3, \3)",
  "\2\7 refers to vertex \3, out of range (\3 vertices)",
  "\2\7: (\3, \3) is not an edge of the mesh",
  "\2\7: (\3, \3) lies on the image border",
  "\2\7: edge (\3, \3) is already a crease",
  "\2\7: edge (\3, \3) is already a feature edge",
  "\2feature \3 (id \3) has fewer than two vertices",
  "\1colors: the tears give \3 color values, but \3 are declared",
  "\1colors: residual out of range",
  "\1colors: value out of range",
  "\2vertex \3 position \10 is not finite",
  "\2vertex \3 position \10 is outside the image [0, \3] x [0, \3]",
  "\2color \3 (\4, \4, \4) is not finite",
  "\2triangle_colors \3 refers to color \3, out of range (\3 colors)",
  "\2feature \3 repeats id \3 (ids must be unique within a level)",
  "\2feature \3 (id \3) saliency \4 is not finite",
  "\2triangle \3 (\3, \3, \3) is flipped or degenerate (signed area \4)",
  "\2vertex \3 \10 is used by no triangle",
  "\2edge (\3, \3) from \10 to \10 has a triangle on one side only but does not lie on the image border (a gap or a hole in the mesh)",
  "\2no vertex at the image corner (\4, \4)",
  "\2triangles \5 around vertex \3 \10: their angles there sum to \4*pi, \5 needs \4*pi",
  "\2the triangles cover an area of \4 but the image has \4 (\3 x \3): they overlap or leave a gap",
  "\2color \3 is used at vertex \3 (triangle \3) and at vertex \3 (triangle \3); a color value belongs to one vertex",
  "\2color \3 is used by no triangle corner",
  "\2edge (\3, \3) is not a tear but triangles \3 and \3 use different colors at vertex \3 (\3 and \3)",
  "\2vertex \3 position \10 is more than 2^24 pixels away",
  "\2has no triangles",
  "\2vertex \3 \10 is on \3 boundary edges (an object's boundary is made of closed loops, two edges at each vertex)",
  "\2triangles overlap around vertex \3 \10: their angles there sum to \4*pi",
  "\5 \3 is not positive",
  "\5 \3 is over the limit of 65536",
  "image size \3 x \3 is over the limit of 1073741824 pixels",
  "the image has no levels",
  "\2level 0 has no level before it, but names parent vertices or collapses",
  "\2\3 parent vertices for \3 vertices",
  "\2\3 collapses do not take level \3's \3 vertices to \3",
  "\2parent vertex \3 is \3, out of range",
  "\2parent vertex \3 appears twice",
  "\2collapse \3 (\3, \3) is out of range",
  "\2collapse \3 removes vertex \3, which is kept or already removed",
  "\2level \3 is out of range (\3 levels)",
  "\2name is not UTF-8",
  "\2an object has no parent vertices or collapses",
  "\2stroke \3: level \3 is not the object's level \3",
  "\2has fewer than two points",
  "\2point \3 (\4, \4) is not finite",
  "\2width \4 is not a positive number",
  "\2color (\4, \4, \4) is not finite",
  "\2taper \4 is outside [0, 0.5]",
};
static const char *const WORDS[] = {"connectivity", "split offsets", "positions", "features", "feature steps", "colors", "header",
                                    "overlap", "leave a gap", "an image corner", "a border vertex", "an interior vertex", "width", "height"};

static void say_level(const char *end) {
  if (message_prefix == 3 && message_owner >= 0) say("object "), say_number(AS_INTEGER, message_owner), say(" ");
  say(message_prefix == 3 ? "stroke " : message_prefix == 2 ? "object " : "level ");
  say_number(AS_INTEGER, message_level);
  say(end);
}

void fail_code(int32_t code, double a, double b, double c, double d, double e, double f, double g) {
  const double args[] = {a, b, c, d, e, f, g};
  const double *next = args;
  say_start();
  for (const char *t = TEMPLATES[code]; *t; ++t) {
    switch (*t) {
    case 1: say_level(" "); break;
    case 2: if (message_prefix) say_level(": "); break;
    case 3: say_number(AS_INTEGER, *next++); break;
    case 4: say_number(AS_G, *next++); break;
    case 5: say(WORDS[(int32_t)*next++]); break;
    case 6:
    case 7:
      say(*next++ != 0 ? "feature " : "crease ");
      say_number(AS_INTEGER, *next++);
      if (*t == 7 && next[-2] != 0) say(" (id "), say_number(AS_INTEGER, *next), say(")");
      next += *t == 7;
      break;
    case 8: {
      int32_t v = (int32_t)*next++;
      say("("), say_number(AS_G, message_positions[2 * v]), say(", "), say_number(AS_G, message_positions[2 * v + 1]), say(")");
      break;
    }
    case 14:
      if (next[1] < 0) say(WORDS[(int32_t)next[0]]);
      else say("feature "), say_number(AS_INTEGER, next[1]);
      next += 2;
      break;
    default: say_bytes((const uint8_t *)t, 1);
    }
  }
  say_fail();
}
