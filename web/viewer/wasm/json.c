// Reading files (docs/format.md), ports of what decode.ts had, itself the C++ reader's checks and
// messages (src/io/svec_json.cpp, svec.cpp, svec_binary.cpp):
// - the .svec.json form: an exact tokenizer (duplicate keys, integers vs numbers, depth 32,
//   byte, line and column of a syntax error), then a walk that names the path of each problem
//   ("levels[0].triangles[12][1]: ..."); numerals and string literals are JavaScript's to read
//   (Number(), JSON.parse on strict UTF-8);
// - the binary form: the header and the zstd frame's header and blocks (fzstd, in JavaScript,
//   decompresses), then the payload: a cursor that names what it was reading, the version-1
//   levels, the compact levels' counts and sections (decode.c decodes them), the objects and
//   their strokes, strokes, metadata and pyramid records.
// Numbers in messages are written by JavaScript (message.h). Both readers end with the image-wide
// rules (validate.c); wasm.ts reads the JsonImage (image.h) back.
#include "image.h"
#include "message.h"

IMPORT(number) double js_number(const uint8_t *text, int32_t n);
IMPORT(string) int32_t js_string(const uint8_t *literal, int32_t n, uint8_t *out);

enum { K_NULL, K_FALSE, K_TRUE, K_INT, K_FRAC, K_STR, K_ARR, K_OBJ };
#define MAX_ELEMENTS 67108864.0
#define MAX_LEVELS 64

typedef struct Node {
  struct Node *next, *first; // siblings; a container's children
  const struct Node *owner;  // an object member's object
  const uint8_t *s, *key;    // a string's UTF-8; an object member's key
  int32_t n, keyn, kind;     // a string's length or a container's count; the key's length
  double v;
} Node;

static const uint8_t *b;
static int32_t len, i, depth;
static struct { int32_t object, keyn, index; const uint8_t *key; } frames[32];

static void *need_memory(void *p) {
  if (!p) say_start(), say("out of memory: the image needs more than WebAssembly can hold"), say_fail();
  return p;
}
static int ch(int32_t at) { return at >= 0 && at < len ? b[at] : -1; }
static void space(void) {
  while (ch(i) == 32 || ch(i) == 9 || ch(i) == 10 || ch(i) == 13) ++i;
}
static void say_index(int32_t k) { say("["), say_number(AS_INTEGER, k), say("]"); }

static void say_path(int top_key) {
  int said_any = 0;
  for (int32_t k = 0; k < depth; ++k) {
    if (!frames[k].object) {
      if (frames[k].index >= 0) say_index(frames[k].index), said_any = 1;
    } else if (frames[k].keyn && (top_key || k + 1 < depth)) {
      if (said_any) say(".");
      say_bytes(frames[k].key, frames[k].keyn), said_any = 1;
    }
  }
  if (!said_any) say("(top level)");
}

__attribute__((noreturn)) static void syntax(const char *what) {
  int32_t end = i < len ? i : len, line = 1, column = 1;
  for (int32_t k = 0; k < end; ++k) b[k] == 10 ? (++line, column = 1) : ++column;
  say_start(), say("invalid JSON near "), say_path(1), say(" (byte "), say_number(AS_INTEGER, (double)i + 1);
  say("): parse error at line "), say_number(AS_INTEGER, line), say(", column "), say_number(AS_INTEGER, column);
  say(": syntax error - "), say(what), say_fail();
}

// A string literal at i: its UTF-8 into node->s. JavaScript reads it (JSON.parse's escapes, the
// bytes valid UTF-8, no lone surrogate) and writes its UTF-8 (never longer than the literal).
static void string(Node *node) {
  int32_t from = i++;
  while (i < len && b[i] != 34) i += b[i] == 92 ? 2 : 1;
  if (i++ >= len) syntax("invalid string: missing closing quote");
  uint8_t *out = (uint8_t *)need_memory(alloc((size_t)(i - from)));
  int32_t n = js_string(b + from, i - from, out);
  if (n < 0) syntax("invalid string");
  node->kind = K_STR, node->s = out, node->n = n;
}

static int same(const uint8_t *a, int32_t an, const uint8_t *c, int32_t cn) {
  if (an != cn) return 0;
  for (int32_t k = 0; k < an; ++k)
    if (a[k] != c[k]) return 0;
  return 1;
}
// The keys read so far, by object: an open-addressed table of members, doubled at half full.
static Node **table;
static uint32_t slots, used;
static uint32_t slot(const Node *owner, const uint8_t *key, int32_t n) {
  uint32_t h = (uint32_t)(uintptr_t)owner * 2654435761u;
  for (int32_t k = 0; k < n; ++k) h = (h ^ key[k]) * 16777619u;
  for (h &= slots - 1; table[h] && !(table[h]->owner == owner && same(table[h]->key, table[h]->keyn, key, n)); h = (h + 1) & (slots - 1)) {}
  return h;
}
// 0 when owner already has the key.
static int remember(Node *member) {
  if (2 * (used + 1) > slots) {
    Node **old = table;
    uint32_t n = slots;
    slots = slots ? 2 * slots : 64, used = 0;
    table = (Node **)need_memory(NEW(Node *, slots));
    for (uint32_t k = 0; k < n; ++k)
      if (old[k]) table[slot(old[k]->owner, old[k]->key, old[k]->keyn)] = old[k], ++used;
  }
  uint32_t h = slot(member->owner, member->key, member->keyn);
  if (table[h]) return 0;
  table[h] = member, ++used;
  return 1;
}

static int is_digit(int c) { return c >= '0' && c <= '9'; }

static Node *value(void) {
  Node *node = (Node *)need_memory(alloc(sizeof(Node)));
  space();
  int c = ch(i);
  if (c == '{' || c == '[') {
    if (depth >= 32) say_start(), say_path(1), say(": JSON nested deeper than 32 levels"), say_fail();
    int object = c == '{', close = object ? '}' : ']';
    int32_t f = depth++;
    frames[f].object = object, frames[f].keyn = 0, frames[f].index = -1;
    node->kind = object ? K_OBJ : K_ARR;
    Node **tail = &node->first;
    ++i;
    space();
    if (ch(i) == close) ++i;
    else
      for (;;) {
        Node *child;
        if (object) {
          space();
          if (ch(i) != '"') syntax("expected string literal");
          Node key;
          string(&key);
          frames[f].key = key.s, frames[f].keyn = key.n;
          key.owner = node, key.key = key.s, key.keyn = key.n;
          if (!remember(&key)) say_start(), say_path(0), say(": duplicate key \""), say_bytes(key.s, key.n), say("\""), say_fail();
          space();
          if (ch(i++) != ':') syntax("expected ':'");
          child = value();
          child->key = key.s, child->keyn = key.n, child->owner = node;
          table[slot(node, key.s, key.n)] = child;
        } else ++frames[f].index, child = value();
        *tail = child, tail = &child->next, ++node->n;
        space();
        int d = ch(i++);
        if (d == close) break;
        if (d != ',') syntax(object ? "expected ',' or '}'" : "expected ',' or ']'");
      }
    --depth;
    return node;
  }
  if (c == '"') return string(node), node;
  int32_t p = i;
  if (ch(p) == '-') ++p;
  if (ch(p) == '0') ++p;
  else if (ch(p) >= '1' && ch(p) <= '9')
    while (is_digit(ch(p))) ++p;
  else p = -1;
  if (p >= 0) {
    int integer = 1;
    if (ch(p) == '.' && is_digit(ch(p + 1))) {
      for (p += 1; is_digit(ch(p)); ++p) {}
      integer = 0;
    }
    int32_t e = p + 1 + (ch(p + 1) == '+' || ch(p + 1) == '-');
    if ((ch(p) | 32) == 'e' && is_digit(ch(e))) {
      for (p = e; is_digit(ch(p)); ++p) {}
      integer = 0;
    }
    double v = js_number(b + i, p - i);
    if (v - v != 0) {
      say_start(), say("invalid JSON at "), say_path(1), say(": number overflow parsing '"), say_bytes(b + i, p - i), say("'"), say_fail();
    }
    i = p;
    if (integer && v >= -9223372036854775808.0 && v < 18446744073709551616.0) node->kind = K_INT, node->v = v + 0;
    else node->kind = K_FRAC, node->v = v; // a fraction, an exponent, or beyond 64 bits: the same below
    return node;
  }
  static const char *const literals[] = {"null", "false", "true"};
  for (int k = 0; k < 3; ++k) {
    const char *w = literals[k];
    int32_t q = 0;
    while (w[q] && ch(i + q) == w[q]) ++q;
    if (!w[q]) return i += q, node->kind = K_NULL + k, node;
  }
  syntax(c < 0 ? "unexpected end of input" : "invalid literal");
}

// ---------------------------------------------------------------------------------------------
// The walk.

typedef struct Path { const struct Path *up; const uint8_t *key; int32_t keyn, index; } Path;

static void say_p(const Path *p) {
  if (!p) return;
  say_p(p->up);
  if (!p->key) say_index(p->index);
  else {
    if (p->up) say(".");
    say_bytes(p->key, p->keyn);
  }
}
static void bad_start(const Path *p) {
  say_start();
  if (p) say_p(p);
  else say("(top level)");
  say(": ");
}
static const char *type_name(const Node *j) {
  static const char *const names[] = {"null", "a boolean", "a boolean", "an integer", "a number with a fraction or exponent", "a string", "an array", "an object"};
  return names[j->kind];
}
__attribute__((noreturn)) static void expected(const Path *p, const char *what, const Node *j) {
  bad_start(p), say("expected "), say(what), say(", got "), say(type_name(j)), say_fail();
}
#define AT_KEY(name, up_, k) const Path name = {up_, (const uint8_t *)(k), sizeof(k) - 1, 0}
#define AT_INDEX(name, up_, k) const Path name = {up_, 0, 0, k}

static Node *find(const Node *m, const char *key) {
  int32_t n = 0;
  while (key[n]) ++n;
  for (Node *c = m->first; c; c = c->next)
    if (same(c->key, c->keyn, (const uint8_t *)key, n)) return c;
  return 0;
}
static Node *need(const Node *m, const Path *p, const char *key) {
  Node *c = find(m, key);
  if (!c) bad_start(p), say("missing key \""), say(key), say("\""), say_fail();
  return c;
}
static double number(const Node *j, const Path *p) {
  if (j->kind != K_INT && j->kind != K_FRAC) expected(p, "a number", j);
  return j->v;
}
static double to_float(const Node *j, const Path *p) {
  double v = number(j, p);
  if (__builtin_fabs(v) > 3.4028234663852886e38)
    bad_start(p), say("number "), say_number(AS_DUMP, v), say(" is out of range for a 32-bit float"), say_fail();
  return (float)v;
}
static double to_int(const Node *j, const Path *p) {
  if (j->kind != K_INT) {
    bad_start(p), say("expected an integer, got "), say(type_name(j));
    if (j->kind == K_FRAC) say(" ("), say_number(AS_DUMP, j->v), say(")");
    say_fail();
  }
  if (j->v < -2147483648.0 || j->v > 2147483647.0)
    bad_start(p), say("integer "), say_number(AS_INTEGER, j->v), say(" is out of the 32-bit range"), say_fail();
  return j->v;
}
static const Node *object(const Node *j, const Path *p) {
  if (j->kind != K_OBJ) expected(p, "an object", j);
  return j;
}
// UTF-16 order of UTF-8 strings: the characters from U+E000 sort after the supplementary ones.
static int before(const Node *a, const Node *c) {
  for (int32_t k = 0;; ++k) {
    if (k == c->keyn) return 0;
    if (k == a->keyn) return 1;
    int x = a->key[k], y = c->key[k];
    if (x != y) return (x == 0xee || x == 0xef ? x + 7 : x) < (y == 0xee || y == 0xef ? y + 7 : y);
  }
}
static const Node *known(const Node *m, const Path *p, const char *allowed) {
  object(m, p);
  const Node *unknown = 0;
  for (const Node *c = m->first; c; c = c->next) {
    int ok = 0;
    for (const char *a = allowed; *a;) {
      int32_t n = 0;
      while (a[n] && a[n] != ',') ++n;
      if (same(c->key, c->keyn, (const uint8_t *)a, n)) ok = 1;
      a += n + (a[n] ? 2 : 0);
    }
    if (!ok && (!unknown || before(c, unknown))) unknown = c;
  }
  if (unknown) bad_start(p), say("unknown key \""), say_bytes(unknown->key, unknown->keyn), say("\" (expected one of: "), say(allowed), say(")"), say_fail();
  return m;
}
static const Node *list(const Node *j, const Path *p) {
  if (j->kind != K_ARR) expected(p, "an array", j);
  if (j->n > MAX_ELEMENTS) bad_start(p), say_number(AS_INTEGER, j->n), say(" elements is over the limit of 67108864"), say_fail();
  return j;
}
typedef double Read(const Node *, const Path *);
enum { F64, F32, I32 };
static void store(void *out, int type, int32_t k, double v) {
  if (type == F64) ((double *)out)[k] = v;
  else if (type == F32) ((float *)out)[k] = (float)v;
  else ((int32_t *)out)[k] = (int32_t)v;
}
static void tuple(const Node *t, const Path *p, int32_t n, const char *shape, Read *read, void *out, int type, int32_t at) {
  if (t->kind != K_ARR || t->n != n) {
    bad_start(p), say("expected "), say(shape), say(", got ");
    if (t->kind == K_ARR) say("an array of "), say_number(AS_INTEGER, t->n), say(" elements");
    else say(type_name(t));
    say_fail();
  }
  int32_t k = 0;
  for (const Node *x = t->first; x; x = x->next, ++k) {
    AT_INDEX(q, p, k);
    store(out, type, at + k, read(x, &q));
  }
}
static Array tuples(int type, const Node *j, const Path *p, int32_t n, const char *shape, Read *read) {
  const Node *items = list(j, p);
  Array a = {n * items->n, need_memory(alloc_array(type == F64 ? 8 : 4, (double)n * items->n + 1))};
  int32_t k = 0;
  for (const Node *t = items->first; t; t = t->next, ++k) {
    AT_INDEX(q, p, k);
    tuple(t, &q, n, shape, read, a.data, type, n * k);
  }
  return a;
}
static Array ints(const Node *j, const Path *p) {
  const Node *items = list(j, p);
  Array a = {items->n, need_memory(alloc_array(4, (double)items->n + 1))};
  int32_t k = 0;
  for (const Node *x = items->first; x; x = x->next, ++k) {
    AT_INDEX(q, p, k);
    ((int32_t *)a.data)[k] = (int32_t)to_int(x, &q);
  }
  return a;
}
#define TRIANGLE "[a, b, c] (three integers)"

static int32_t length(const char *s) {
  int32_t n = 0;
  while (s[n]) ++n;
  return n;
}
// m's `key`: a number read as `type` (out null), a list of n-tuples (n > 0) or of integers (n 0)
// into *out; `otherwise` when absent (NaN: required). Returns otherwise, 1 or the number.
static double field(const Node *m, const Path *up, const char *key, int type, int n, const char *shape, double otherwise, Array *out) {
  const Path p = {up, (const uint8_t *)key, length(key), 0};
  const Node *j = find(m, key);
  if (!j) {
    if (otherwise != otherwise) need(m, up, key);
    return otherwise;
  }
  Read *read = type == F64 ? number : type == F32 ? to_float : to_int;
  if (!out) return read(j, &p);
  *out = n ? tuples(type, j, &p, n, shape, read) : ints(j, &p);
  return 1;
}
#define REQUIRED __builtin_nan("")

#define MAX_OBJECTS 4096

// JSON.stringify of a value (format's), numbers as String().
static void say_json(const Node *j, int nested) {
  if (j->kind == K_STR) {
    say("\"");
    for (int32_t k = 0; k < j->n; ++k) {
      uint8_t c = j->s[k];
      const char *e = c == '"' ? "\\\"" : c == '\\' ? "\\\\" : c == 8 ? "\\b" : c == 12 ? "\\f" : c == 10 ? "\\n" : c == 13 ? "\\r" : c == 9 ? "\\t" : 0;
      if (e) say(e);
      else if (c < 0x20) {
        char u[7] = "\\u00";
        u[4] = "0123456789abcdef"[c >> 4], u[5] = "0123456789abcdef"[c & 15], u[6] = 0;
        say(u);
      } else say_bytes(&c, 1);
    }
    say("\"");
  } else if (j->kind == K_INT || j->kind == K_FRAC) {
    // decode.ts held an integral number written with a fraction or exponent as an object, and
    // JSON.stringify wrote it so inside an array
    int boxed = nested && j->kind == K_FRAC && j->v == __builtin_trunc(j->v);
    if (boxed) say("{\"value\":");
    say_number(AS_INTEGER, j->v);
    if (boxed) say("}");
  } else if (j->kind == K_ARR) {
    say("[");
    for (const Node *x = j->first; x; x = x->next) say_json(x, 1), x->next ? say(",") : (void)0;
    say("]");
  } else say(j->kind == K_OBJ ? "{}" : j->kind == K_NULL ? "null" : j->kind == K_TRUE ? "true" : "false");
}

// A level object at p (a level's, or an object's mesh) into *level.
static void json_level(const Node *j, const Path *p, JsonLevel *level) {
  const Node *m = known(j, p, "vertices, colors, triangles, triangle_colors, creases, features, parent_vertices, collapses");
  AT_KEY(ptc, p, "triangle_colors");
  field(m, p, "vertices", F64, 2, "[x, y]", REQUIRED, &level->positions);
  field(m, p, "colors", F32, 3, "[r, g, b]", REQUIRED, &level->colors);
  field(m, p, "triangles", I32, 3, TRIANGLE, REQUIRED, &level->triangles);
  if (field(m, p, "triangle_colors", I32, 3, TRIANGLE, 0, &level->triangle_colors) != 0) {
    if (level->triangle_colors.n != level->triangles.n)
      bad_start(&ptc), say_number(AS_INTEGER, level->triangle_colors.n / 3), say(" entries but there are "), say_number(AS_INTEGER, level->triangles.n / 3),
        say(" triangles (one entry per triangle)"), say_fail();
  } else if (level->colors.n / 3 != level->positions.n / 2) {
    bad_start(p), say("\"triangle_colors\" is absent, so color i belongs to vertex i, but there are "), say_number(AS_INTEGER, level->positions.n / 2),
      say(" vertices and "), say_number(AS_INTEGER, level->colors.n / 3), say(" colors"), say_fail();
  } else level->triangle_colors = level->triangles; // a copy (wasm.ts copies each array out)
  const Node *o;
  field(m, p, "creases", I32, 2, "[a, b] (two vertex indices)", 0, &level->creases);
  AT_KEY(pfe, p, "features");
  if ((o = find(m, "features"))) {
    const Node *fs = list(o, &pfe);
    level->num_features = fs->n, level->feature_ids = NEW(int32_t, fs->n + 1), level->saliency = NEW(double, fs->n + 1);
    level->feature_vertices = NEW(Array, fs->n + 1);
    need_memory(level->feature_ids), need_memory(level->saliency), need_memory(level->feature_vertices);
    int32_t k = 0;
    for (const Node *f = fs->first; f; f = f->next, ++k) {
      AT_INDEX(r, &pfe, k);
      const Node *fo = known(f, &r, "id, vertices, saliency");
      level->feature_ids[k] = (int32_t)field(fo, &r, "id", I32, 0, 0, REQUIRED, 0);
      field(fo, &r, "vertices", I32, 0, 0, REQUIRED, &level->feature_vertices[k]);
      level->saliency[k] = field(fo, &r, "saliency", F64, 0, 0, 0, 0);
    }
  }
  field(m, p, "parent_vertices", I32, 0, 0, 0, &level->parents);
  field(m, p, "collapses", I32, 2, "[removed, kept] (two vertex indices)", 0, &level->collapses);
}

// m's "strokes" (the image's, or an object's), when it has them, into *out.
static void json_strokes(const Node *m, const Path *up, Strokes *out) {
  AT_KEY(ps, up, "strokes");
  const Node *o = find(m, "strokes");
  if (!o) return;
  const Node *ss = list(o, &ps);
  out->n = ss->n, out->items = (JsonStroke *)need_memory(NEW(JsonStroke, ss->n + 1));
  int32_t k = 0;
  for (const Node *j = ss->first; j; j = j->next, ++k) {
    AT_INDEX(p, &ps, k);
    const Node *s = known(j, &p, "level, points, width, color, taper");
    JsonStroke *stroke = &out->items[k];
    AT_KEY(pcl, &p, "color");
    stroke->level = (int32_t)field(s, &p, "level", I32, 0, 0, 0, 0);
    field(s, &p, "points", F64, 2, "[x, y]", REQUIRED, &stroke->points);
    stroke->width = (float)field(s, &p, "width", F32, 0, 0, REQUIRED, 0);
    tuple(need(s, &p, "color"), &pcl, 3, "[r, g, b]", to_float, stroke->color, F32, 0);
    stroke->taper = (float)field(s, &p, "taper", F32, 0, 0, 0.25, 0);
  }
}

EXPORT(json) JsonImage *json(const uint8_t *bytes, int32_t n) {
  b = bytes, len = n, i = depth = 0, table = 0, slots = used = 0;
  const Node *top = value();
  space();
  if (i < len) syntax("unexpected character after the value; expected end of input");
  if (top->kind != K_OBJ) bad_start(0), say("expected a JSON object, got "), say(type_name(top)), say_fail();
  const Node *format = need(top, 0, "format");
  AT_KEY(pf, 0, "format");
  if (!(format->kind == K_STR && same(format->s, format->n, (const uint8_t *)"subvec", 6)))
    bad_start(&pf), say("expected \"subvec\", got "), say_json(format, 0), say(" (this is not a subvec file)"), say_fail();
  AT_KEY(pv, 0, "version");
  double version = field(top, 0, "version", I32, 0, 0, REQUIRED, 0);
  if (version != 1 && version != 2)
    bad_start(&pv), say("unsupported .svec.json version "), say_number(AS_INTEGER, version), say(" (this build reads 1 and 2)"), say_fail();
  known(top, 0, version == 1 ? "format, version, width, height, levels, strokes, metadata" : "format, version, width, height, levels, objects, strokes, metadata");
  JsonImage *image = (JsonImage *)need_memory(alloc(sizeof(JsonImage)));
  AT_KEY(pl, 0, "levels");
  image->width = (int32_t)field(top, 0, "width", I32, 0, 0, REQUIRED, 0), image->height = (int32_t)field(top, 0, "height", I32, 0, 0, REQUIRED, 0);
  const Node *items = list(need(top, 0, "levels"), &pl);
  if (items->n > MAX_LEVELS) bad_start(&pl), say_number(AS_INTEGER, items->n), say(" levels is over the limit of 64"), say_fail();
  image->num_levels = items->n, image->levels = (JsonLevel *)need_memory(NEW(JsonLevel, items->n + 1));
  int32_t l = 0;
  for (const Node *j = items->first; j; j = j->next, ++l) {
    AT_INDEX(p, &pl, l);
    json_level(j, &p, &image->levels[l]);
  }
  const Node *o;
  AT_KEY(po, 0, "objects");
  if ((o = find(top, "objects"))) {
    const Node *os = list(o, &po);
    if (os->n > MAX_OBJECTS) bad_start(&po), say_number(AS_INTEGER, os->n), say(" objects is over the limit of 4096"), say_fail();
    image->num_objects = os->n, image->objects = (JsonObject *)need_memory(NEW(JsonObject, os->n + 1));
    int32_t k = 0;
    for (const Node *j = os->first; j; j = j->next, ++k) {
      AT_INDEX(p, &po, k);
      const Node *m = known(j, &p, "level, name, visible, mesh, strokes"), *x;
      JsonObject *object = &image->objects[k];
      object->level = (int32_t)field(m, &p, "level", I32, 0, 0, 0, 0), object->visible = 1;
      AT_KEY(pn, &p, "name");
      if ((x = find(m, "name"))) {
        if (x->kind != K_STR) expected(&pn, "a string", x);
        object->name = x->s, object->namen = x->n;
      }
      AT_KEY(pvi, &p, "visible");
      if ((x = find(m, "visible"))) {
        if (x->kind != K_TRUE && x->kind != K_FALSE) expected(&pvi, "true or false", x);
        object->visible = x->kind == K_TRUE;
      }
      AT_KEY(pme, &p, "mesh");
      json_level(need(m, &p, "mesh"), &pme, &object->mesh);
      json_strokes(m, &p, &object->strokes);
    }
  }
  json_strokes(top, 0, &image->strokes);
  AT_KEY(pm, 0, "metadata");
  if ((o = find(top, "metadata"))) {
    const Node *mm = object(o, &pm);
    image->num_metadata = mm->n, image->metadata = (JsonEntry *)need_memory(NEW(JsonEntry, mm->n + 1));
    int32_t k = 0;
    for (const Node *x = mm->first; x; x = x->next, ++k) {
      if (x->kind != K_STR) {
        const Path q = {&pm, x->key, x->keyn, 0};
        expected(&q, "a string", x);
      }
      image->metadata[k] = (JsonEntry){x->key, x->keyn, x->s, x->n};
    }
  }
  validate_image(image);
  return image;
}

// ---------------------------------------------------------------------------------------------
// The binary form's payload (docs/format.md), as the zstd frame gave it: a bounds-checked
// little-endian cursor that names what it was reading when the bytes run out; the compact levels
// by decode.c.

typedef struct { const uint8_t *bytes; int32_t length; } Section;
void *compact(int32_t version, const Section *sections, double ops, int32_t nv, int32_t ncolors, int32_t ntriangles, int32_t ncreases,
              int32_t nfeatures, int32_t pb, int32_t cb, double width, double height, int32_t level);

static int32_t pos, what_count;
static char what[96];

// what = fmt with its #s replaced by a, then b.
static void name(const char *fmt, int32_t a, int32_t c) {
  int32_t n = 0;
  for (; *fmt; ++fmt) {
    if (*fmt != '#') {
      what[n++] = *fmt;
      continue;
    }
    char digits[12];
    int32_t d = 0;
    for (uint32_t v = (uint32_t)a; d == 0 || v; v /= 10) digits[d++] = (char)('0' + v % 10);
    while (d) what[n++] = digits[--d];
    a = c;
  }
  what[n] = 0;
}
static void say_what(void) {
  say(what);
  if (what_count) say(" count");
}
static int32_t left(void) { return len - pos; }
static int32_t take(double n) {
  int32_t p = pos;
  if (n > left())
    say_start(), say("truncated payload while reading "), say_what(), say(" (needs "), say_number(AS_INTEGER, n), say(" bytes at offset "),
      say_number(AS_INTEGER, p), say(", "), say_number(AS_INTEGER, left()), say(" left)"), say_fail();
  pos += (int32_t)n;
  return p;
}
static uint32_t u32(void) {
  uint32_t v;
  __builtin_memcpy(&v, b + take(4), 4);
  return v;
}
static double f32(void) {
  float v;
  __builtin_memcpy(&v, b + take(4), 4);
  return v;
}
static double f64(void) {
  double v;
  __builtin_memcpy(&v, b + take(8), 8);
  return v;
}
// n values of `size` bytes, copied (aligned); short of bytes, it fails where reading them one by
// one would.
static Array array(double n, int32_t size) {
  int32_t fit = n < left() / size ? (int32_t)n : left() / size;
  Array a = {(int32_t)n, need_memory(alloc_array((size_t)size, n + 1))};
  __builtin_memcpy(a.data, b + pos, (size_t)(fit * size));
  pos += fit * size;
  if (fit < n) take(size);
  return a;
}
// Unsigned LEB128 of at most 64 bits; exact below 2^53, which every range check lies below.
static double varint(void) {
  double v = 0, scale = 1;
  for (int shift = 0;; shift += 7, scale *= 128) {
    uint32_t c = b[take(1)];
    if (shift == 63 && c > 1) say_start(), say("malformed varint while reading "), say_what(), say_fail();
    v += (c & 0x7f) * scale;
    if (c < 128) return v;
  }
}
// An element count, capped by `max` and by the bytes left (each element takes `min` or more).
static int32_t count(double min, double max) {
  what_count = 1;
  double n = u32();
  what_count = 0;
  if (n > max) say_start(), say(what), say(": count "), say_number(AS_INTEGER, n), say(" is over the limit of "), say_number(AS_INTEGER, max), say_fail();
  if (n * min > left())
    say_start(), say("truncated payload while reading "), say(what), say(" ("), say_number(AS_INTEGER, n), say(" declared, needing "), say_number(AS_INTEGER, n * min),
      say(" bytes at offset "), say_number(AS_INTEGER, pos), say(", "), say_number(AS_INTEGER, left()), say(" left)"), say_fail();
  return (int32_t)n;
}
static Array string_of(const char *fmt, int32_t a) {
  name(fmt, a, 0);
  int32_t n = count(1, MAX_ELEMENTS);
  Array s = {n, (void *)(b + take(n))};
  return s;
}

static const char *const SECTIONS[] = {"connectivity", "split offsets", "positions", "features", "feature steps", "colors"};
static const char *const COUNTS[] = {"vertices", "colors", "triangles", "creases", "features"};
// what = "level l " + w, or "object l " + w (mesh_prefix)
static const char *mesh_prefix = "level # ";
static void level_name(const char *w, int32_t l, int32_t k) {
  char fmt[48];
  int32_t q = 0;
  for (const char *m = mesh_prefix; *m;) fmt[q++] = *m++;
  while (*w) fmt[q++] = *w++;
  fmt[q] = 0;
  name(fmt, l, k);
}

static const double MIN[] = {16, 12, 24, 8, 16};
// A mesh in the version-1 layout (a level's, or an object's), named by mesh_prefix and l.
static void mesh_v1(JsonLevel *level, int32_t l) {
  int32_t c[5];
  for (int k = 0; k < 5; ++k) level_name(COUNTS[k], l, 0), c[k] = count(MIN[k], MAX_ELEMENTS);
  level_name("vertices", l, 0), level->positions = array(2.0 * c[0], 8);
  level_name("colors", l, 0), level->colors = array(3.0 * c[1], 4);
  level_name("triangles", l, 0), level->triangles = array(3.0 * c[2], 4);
  level_name("triangle colors", l, 0), level->triangle_colors = array(3.0 * c[2], 4);
  level_name("creases", l, 0), level->creases = array(2.0 * c[3], 4);
  level->num_features = c[4], level->feature_ids = NEW(int32_t, c[4] + 1), level->saliency = NEW(double, c[4] + 1);
  level->feature_vertices = NEW(Array, c[4] + 1);
  need_memory(level->feature_ids), need_memory(level->saliency), need_memory(level->feature_vertices);
  for (int32_t k = 0; k < c[4]; ++k) {
    level_name("feature #", l, k);
    level->feature_ids[k] = (int32_t)u32(), level->saliency[k] = f64();
    level_name("feature # vertices", l, k);
    level->feature_vertices[k] = array(count(4, MAX_ELEMENTS), 4);
  }
}

// base + delta (a zigzag code) as a vertex index; both are checked before they are added.
static int32_t vertex_index(int32_t record, double base, double code) {
  double half = __builtin_floor(code / 2), delta = code - 2 * half != 0 ? -(code + 1) / 2 : code / 2;
  if (__builtin_fabs(delta) > 4294967296.0 || base + delta < 0 || base + delta > 2147483647.0)
    say_start(), say("pyramid record "), say_number(AS_INTEGER, record), say(": a vertex index is out of range"), say_fail();
  return (int32_t)(base + delta);
}

// Strokes as the trailer holds them, named by mesh_prefix ("": the image's, with `owner` unused;
// "object # ": object `owner`'s).
static void binary_strokes(int32_t owner, Strokes *out) {
  int by_object = *mesh_prefix != 0;
  level_name("strokes", owner, 0);
  int32_t ns = out->n = count(28, MAX_ELEMENTS);
  out->items = (JsonStroke *)need_memory(NEW(JsonStroke, ns + 1));
  for (int32_t k = 0; k < ns; ++k) {
    JsonStroke *s = &out->items[k];
    level_name("stroke #", by_object ? owner : k, k);
    s->level = (int32_t)u32(), s->width = (float)f32();
    for (int q = 0; q < 3; ++q) s->color[q] = (float)f32();
    s->taper = (float)f32();
    level_name("stroke # points", by_object ? owner : k, k);
    s->points = array(2.0 * count(16, MAX_ELEMENTS), 8);
  }
}

EXPORT(payload) JsonImage *payload(const uint8_t *bytes, int32_t n, int32_t version, int32_t flags) {
  b = bytes, len = n, pos = what_count = 0, mesh_prefix = "level # ";
  JsonImage *image = (JsonImage *)need_memory(alloc(sizeof(JsonImage)));
  name("image size", 0, 0);
  int32_t width = image->width = (int32_t)u32(), height = image->height = (int32_t)u32();
  name("levels", 0, 0);
  int32_t nl = image->num_levels = count(20, MAX_LEVELS);
  if (version > 1 && (width < 1 || height < 1 || width > 65536 || height > 65536))
    say_start(), say("image size "), say_number(AS_INTEGER, width), say(" x "), say_number(AS_INTEGER, height), say(" is out of range (1 to 65536 a side)"), say_fail();
  image->levels = (JsonLevel *)need_memory(NEW(JsonLevel, nl + 1));
  for (int32_t l = 0; l < nl; ++l) {
    JsonLevel *level = &image->levels[l];
    int32_t c[5];
    if (version > 1) {
      for (int k = 0; k < 5; ++k) level_name(COUNTS[k], l, 0), c[k] = count(0, MAX_ELEMENTS);
      name("level # precision", l, 0);
      int32_t pb = b[take(1)], cb = (int8_t)b[take(1)];
      if (pb > 12 || cb < -4 || cb > 12)
        say_start(), say("level "), say_number(AS_INTEGER, l), say(" precision: position bits "), say_number(AS_INTEGER, pb), say(", color bits "), say_number(AS_INTEGER, cb),
          say(" (expected 0 to 12 and -4 to 12)"), say_fail();
      if (c[0] < 3) say_start(), say("level "), say_number(AS_INTEGER, l), say(" vertices: "), say_number(AS_INTEGER, c[0]), say(" (a level has at least 3)"), say_fail();
      double ops = 3.0 * left();
      Section sections[6];
      for (int k = 0; k < (version == 2 ? 6 : 1); ++k) {
        level_name(version == 2 ? SECTIONS[k] : "stream", l, 0);
        int32_t m = count(1, MAX_ELEMENTS * 64);
        sections[k] = (Section){b + take(m), m};
        int32_t expected = (2 * c[0] - 3 + 2) / 3;
        if (version == 2 && k == 0 && m != expected)
          say_start(), say("level "), say_number(AS_INTEGER, l), say(" connectivity: "), say_number(AS_INTEGER, m), say(" bytes for "), say_number(AS_INTEGER, c[0]),
            say(" vertices (expected "), say_number(AS_INTEGER, expected), say(")"), say_fail();
      }
      // decode.c's Level, field by field (32-bit): positions, colors, triangles, triangleColors,
      // creases, numFeatures, featureIds, featureOffsets, featureVertices, featureSaliency, then
      // Edges: numEdges, a, b, f, g (decode.c asserts the layout)
      const int32_t *L = (const int32_t *)compact(version, sections, ops, c[0], c[1], c[2], c[3], c[4], pb, cb, width, height, l);
#define FIELD(k) ((void *)(uintptr_t)L[k])
      level->positions = (Array){2 * c[0], FIELD(0)}, level->colors = (Array){3 * c[1], FIELD(1)}, level->triangles = (Array){3 * c[2], FIELD(2)};
      level->triangle_colors = (Array){3 * c[2], FIELD(3)}, level->creases = (Array){2 * c[3], FIELD(4)};
      level->num_features = c[4], level->feature_ids = FIELD(6), level->saliency = FIELD(9);
      level->feature_vertices = (Array *)need_memory(NEW(Array, c[4] + 1));
      const int32_t *offsets = FIELD(7), *vertices = FIELD(8);
      for (int32_t k = 0; k < c[4]; ++k) level->feature_vertices[k] = (Array){offsets[k + 1] - offsets[k], (void *)(vertices + offsets[k])};
      level->edges = L + 10;
      continue;
    }
    mesh_v1(level, l);
  }
  // The objects (header flag 1): each one's level, visibility, name and a version-1 mesh.
  if (flags & 1) {
    name("objects", 0, 0);
    int32_t no = image->num_objects = count(25, MAX_OBJECTS);
    image->objects = (JsonObject *)need_memory(NEW(JsonObject, no + 1));
    mesh_prefix = "object # ";
    for (int32_t k = 0; k < no; ++k) {
      JsonObject *object = &image->objects[k];
      name("object # header", k, 0);
      object->level = (int32_t)u32();
      int32_t visible = object->visible = b[take(1)];
      if (visible > 1)
        say_start(), say("object "), say_number(AS_INTEGER, k), say(" visibility "), say_number(AS_INTEGER, visible), say(" is neither 0 nor 1"), say_fail();
      Array s = string_of("object # name", k);
      object->name = s.data, object->namen = s.n;
      mesh_v1(&object->mesh, k);
    }
    // The objects' strokes (header flag 2), each object's as the image's.
    if (flags & 2)
      for (int32_t k = 0; k < no; ++k) binary_strokes(k, &image->objects[k].strokes);
  }
  mesh_prefix = "";
  binary_strokes(0, &image->strokes);
  name("metadata entries", 0, 0);
  int32_t nm = image->num_metadata = count(8, MAX_ELEMENTS);
  image->metadata = (JsonEntry *)need_memory(NEW(JsonEntry, nm + 1));
  for (int32_t k = 0; k < nm; ++k) {
    Array key = string_of("metadata entry # key", k), value = string_of("metadata entry # value", k);
    image->metadata[k] = (JsonEntry){key.data, key.n, value.data, value.n};
  }
  // Optional: the pyramid records of levels 1 and up (files written before them end here).
  if (left() && left() < 4) say_start(), say_number(AS_INTEGER, left()), say(" unexpected bytes after the payload's metadata"), say_fail();
  if (left()) {
    name("pyramid records", 0, 0);
    for (int32_t k = 0, nr = count(3, MAX_LEVELS); k < nr; ++k) {
      name("pyramid record #", k, 0);
      uint32_t l = u32();
      JsonLevel *level = l < (uint32_t)nl ? &image->levels[l] : 0;
      if (l < 1 || !level || level->parents.n || level->collapses.n)
        say_start(), say(what), say(": level "), say_number(AS_INTEGER, l), say(" is out of range or named twice"), say_fail();
      name("pyramid record # parent vertices", k, 0);
      Array parents = {count(1, MAX_ELEMENTS), 0}, collapses;
      parents.data = need_memory(NEW(int32_t, parents.n + 1));
      int32_t *pv = (int32_t *)parents.data, previous = 0;
      for (int32_t q = 0; q < parents.n; ++q) pv[q] = previous = vertex_index(k, previous, varint());
      name("pyramid record # collapses", k, 0);
      collapses.n = 2 * count(2, MAX_ELEMENTS);
      int32_t *cv = (int32_t *)(collapses.data = need_memory(NEW(int32_t, collapses.n + 1)));
      for (int32_t q = 0; q < collapses.n; q += 2) {
        double code = varint();
        cv[q] = vertex_index(k, 0, 2 * (code < 1099511627776.0 ? code : 1099511627776.0));
        cv[q + 1] = vertex_index(k, cv[q], varint());
      }
      level->parents = parents, level->collapses = collapses;
    }
  }
  if (left()) say_start(), say_number(AS_INTEGER, left()), say(" unexpected bytes after the payload's pyramid records"), say_fail();
  validate_image(image);
  return image;
}

// ---------------------------------------------------------------------------------------------
// The binary form's header and its zstd frame's header and blocks: the checks libzstd makes that
// fzstd does not (window limit, dictionary, block sizes), and where the frame ends. Returns the
// payload's size, the frame's end (after its checksum; infinite when the blocks run out), what a
// raw block cut short gives, the frame descriptor, the version and the flags.

static void say_u64(uint64_t v) {
  char digits[20];
  int32_t d = 20;
  do digits[--d] = (char)('0' + v % 10), v /= 10;
  while (v);
  say_bytes((const uint8_t *)digits + d, 20 - d);
}
static double le(const uint8_t *f, int32_t at, int32_t n) {
  double v = 0;
  for (int32_t k = n; k--;) v = v * 256 + f[at + k];
  return v;
}

EXPORT(container) double *container(const uint8_t *file, int32_t n) {
  static const uint8_t MAGIC[8] = {0x53, 0x55, 0x42, 0x56, 0x45, 0x43, 0x00, 0x1a};
  for (int32_t k = 0; k < 8 && k < n; ++k)
    if (file[k] != MAGIC[k]) {
      say_start(), say("not a .svec file: wrong magic bytes (");
      for (int32_t q = 0; q < 8 && q < n; ++q) {
        char h[4] = {"0123456789abcdef"[file[q] >> 4], "0123456789abcdef"[file[q] & 15], ' ', 0};
        if (q + 1 == 8 || q + 1 == n) h[2] = 0;
        say(h);
      }
      say(", expected 53 55 42 56 45 43 00 1a)"), say_fail();
    }
  if (n < 32) say_start(), say("truncated .svec header: "), say_number(AS_INTEGER, n), say(" bytes, the header needs 32"), say_fail();
  uint32_t version, flags;
  uint64_t size, frame, available = (uint64_t)(n - 32);
  __builtin_memcpy(&version, file + 8, 4), __builtin_memcpy(&flags, file + 12, 4), __builtin_memcpy(&size, file + 16, 8), __builtin_memcpy(&frame, file + 24, 8);
  if (version < 1 || version > 3) say_start(), say("unsupported .svec version "), say_number(AS_INTEGER, version), say(" (this build reads 1, 2 and 3)"), say_fail();
  if (flags & ~3u) say_start(), say("unsupported .svec flags "), say_number(AS_INTEGER, flags), say(" (this build knows 1: objects, 2: object strokes)"), say_fail();
  if (flags == 2) say_start(), say(".svec flag 2 (object strokes) is set without flag 1 (objects)"), say_fail();
  if (size > 1073741824) say_start(), say("declared payload of "), say_u64(size), say(" bytes is over the limit of 1073741824"), say_fail();
  if (frame > available)
    say_start(), say("truncated .svec file: the header declares a "), say_u64(frame), say("-byte zstd frame but only "), say_u64(available), say(" bytes follow"), say_fail();
  if (frame < available) say_start(), say_u64(available - frame), say(" unexpected bytes after the zstd frame"), say_fail();

  const uint8_t *f = file + 32;
  int32_t fn = n - 32, d = fn > 4 ? f[4] : 0, single = d >> 5 & 1, dict = (int32_t[]){0, 1, 2, 4}[d & 3], size_bytes = (int32_t[]){single, 2, 4, 8}[d >> 6];
  double end = 6 - single + dict + size_bytes, expected = (double)size;
  if (fn < end || le(f, 0, 4) != 4247762216.0 || d & 8) say_start(), say("corrupt zstd frame: bad frame header"), say_fail();
  double content = size_bytes ? le(f, (int32_t)end - size_bytes, size_bytes) + (size_bytes == 2 ? 256 : 0) : -1;
  if (content >= 0 && content != expected)
    say_start(), say("zstd frame holds "), say_number(AS_INTEGER, content), say(" bytes but the header declares "), say_number(AS_INTEGER, expected), say_fail();
  double window = single ? content : (double)(1ull << (10 + (f[5] >> 3))) * (1 + (f[5] & 7) / 8.0);
  if (window > 134217729.0) say_start(), say("corrupt zstd frame: Frame requires too much memory for decoding"), say_fail();
  if (le(f, (int32_t)end - size_bytes - dict, dict) != 0) say_start(), say("corrupt zstd frame: Dictionary mismatch"), say_fail();
  double partial = 0;
  for (int last = 0; !last;) {
    if (end + 3 > fn) {
      end = __builtin_inf();
      break;
    }
    int32_t h = (int32_t)le(f, (int32_t)end, 3), type = h >> 1 & 3, bytes = (int32_t)((uint32_t)h >> 3);
    if (type == 3 || bytes > (window < 131072 ? window : 131072)) say_start(), say("corrupt zstd frame: Data corruption detected"), say_fail();
    last = h & 1;
    partial = type == 0 && fn - end - 3 < bytes ? (fn - end - 3 > 0 ? fn - end - 3 : 0) : 0;
    end += 3 + (type == 1 ? 1 : bytes);
  }
  if (d & 4) end += 4;
  double *out = (double *)need_memory(alloc(6 * sizeof(double)));
  out[0] = expected, out[1] = end, out[2] = partial, out[3] = d, out[4] = version, out[5] = flags;
  return out;
}
