// The image-wide validity rules (validate() of src/mesh/validate.cpp, docs/format.md "Validity
// rules"), checked where the file readers (json.c) leave the image, in the C++ order and with its
// messages: the image's size; each level's rules (decode.c, check_level); the pyramid links;
// each object's level, name, record and mesh (check_object) and strokes; the strokes; the
// metadata. (Counts are capped where they are read.)
#include "image.h"
#include "message.h"

int32_t check_level(int32_t nv, const double *p, int32_t nc, const float *c, int32_t nt, const int32_t *t, const int32_t *tc,
                    int32_t ncreases, const int32_t *creases, int32_t nfeatures, const int32_t *ids, const double *saliency,
                    const int32_t *offsets, const int32_t *verts, double width, double height, const void *built, int32_t level);
int32_t check_object(int32_t nv, const double *p, int32_t nc, const float *c, int32_t nt, const int32_t *t, const int32_t *tc,
                     int32_t ncreases, const int32_t *creases, int32_t nfeatures, const int32_t *ids, const double *saliency,
                     const int32_t *offsets, const int32_t *verts, int32_t index);

static void *need(void *p) {
  if (!p) FAIL(E_OUT_OF_MEMORY);
  return p;
}

// A mesh's rules: an object's (index >= 0) or level l's.
static void check(const JsonLevel *m, const JsonImage *image, int32_t l, int32_t index) {
  int32_t nf = m->num_features, *offsets = (int32_t *)need(NEW(int32_t, nf + 1)), *verts;
  for (int32_t k = 0; k < nf; ++k) offsets[k + 1] = offsets[k] + m->feature_vertices[k].n;
  verts = (int32_t *)need(NEW(int32_t, offsets[nf] + 1));
  for (int32_t k = 0; k < nf; ++k) __builtin_memcpy(verts + offsets[k], m->feature_vertices[k].data, 4 * (size_t)m->feature_vertices[k].n);
  const double *p = (const double *)m->positions.data;
  const float *c = (const float *)m->colors.data;
  const int32_t *t = (const int32_t *)m->triangles.data, *tc = (const int32_t *)m->triangle_colors.data, *cr = (const int32_t *)m->creases.data;
  if (index >= 0)
    check_object(m->positions.n / 2, p, m->colors.n / 3, c, m->triangles.n / 3, t, tc, m->creases.n / 2, cr, nf, m->feature_ids, m->saliency, offsets,
                 verts, index);
  else
    check_level(m->positions.n / 2, p, m->colors.n / 3, c, m->triangles.n / 3, t, tc, m->creases.n / 2, cr, nf, m->feature_ids, m->saliency, offsets,
                verts, image->width, image->height, m->edges, l);
}

// The pyramid link of level l: one parent per vertex, parents distinct and in range, the
// collapses removing exactly the other vertices of level l - 1.
static void check_link(const JsonImage *image, int32_t l) {
  const JsonLevel *m = &image->levels[l];
  const int32_t *parents = (const int32_t *)m->parents.data, *collapses = (const int32_t *)m->collapses.data;
  int32_t np = m->parents.n, n = m->collapses.n / 2;
  if (!np && !n) return;
  message_level = l, message_prefix = 1;
  if (!l) FAIL(L_LEVEL_0);
  int32_t nv = m->positions.n / 2, fine = image->levels[l - 1].positions.n / 2;
  if (np != nv) FAIL(L_PARENT_COUNT, np, nv);
  if (n + nv != fine) FAIL(L_COLLAPSE_COUNT, n, l - 1, fine, nv);
  uint8_t *state = (uint8_t *)need(NEW(uint8_t, fine)); // 1 parent, 2 removed
  for (int32_t i = 0; i < nv; ++i) {
    int32_t v = parents[i];
    if (v < 0 || v >= fine) FAIL(L_PARENT_RANGE, i, v);
    if (state[v]) FAIL(L_PARENT_TWICE, v);
    state[v] = 1;
  }
  for (int32_t i = 0; i < n; ++i) {
    int32_t u = collapses[2 * i], v = collapses[2 * i + 1];
    if (u < 0 || u >= fine || v < 0 || v >= fine || u == v) FAIL(L_COLLAPSE_RANGE, i, u, v);
    if (state[u]) FAIL(L_COLLAPSE_REMOVES, i, u);
    state[u] = 2;
  }
}

static int finite(double v) { return __builtin_isfinite(v); }

// Stroke k: the image's (owner -1), messages "stroke K: ", or object owner's, "object N stroke K: ".
static void check_stroke(const JsonStroke *s, int32_t k, int32_t owner, int32_t levels) {
  const double *p = (const double *)s->points.data;
  message_owner = owner, message_level = k, message_prefix = 3;
  if (s->level < 0 || s->level >= levels) FAIL(O_LEVEL, s->level, levels);
  if (s->points.n < 4) FAIL(S_FEW_POINTS);
  for (int32_t q = 0; q < s->points.n; q += 2)
    if (!finite(p[q]) || !finite(p[q + 1])) FAIL(S_POINT, q / 2, p[q], p[q + 1]);
  if (!(finite(s->width) && s->width > 0)) FAIL(S_WIDTH, s->width);
  if (!finite(s->color[0]) || !finite(s->color[1]) || !finite(s->color[2])) FAIL(S_COLOR, s->color[0], s->color[1], s->color[2]);
  if (!(s->taper >= 0 && s->taper <= 0.5f)) FAIL(S_TAPER, s->taper);
}

// Strict UTF-8 (valid_utf8 of src/mesh/validate.cpp): no overlong forms, surrogates or code
// points past U+10FFFF.
static int utf8(const uint8_t *s, int32_t n) {
  static const uint32_t MIN[4] = {0, 0x80, 0x800, 0x10000};
  for (int32_t i = 0; i < n;) {
    uint32_t c = s[i], cp;
    int extra = c < 0x80 ? 0 : (c & 0xe0) == 0xc0 ? 1 : (c & 0xf0) == 0xe0 ? 2 : (c & 0xf8) == 0xf0 ? 3 : -1;
    if (extra < 0 || i + extra >= n + !extra) return 0;
    cp = c & (0x7f >> extra);
    for (int k = 1; k <= extra; ++k) {
      if ((s[i + k] & 0xc0) != 0x80) return 0;
      cp = cp << 6 | (s[i + k] & 0x3f);
    }
    if (cp < MIN[extra] || cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff)) return 0;
    i += extra + 1;
  }
  return 1;
}

// "metadata entry K" and, with a key, " (key)"/": key" quoted as C++ quotes it: control
// characters as \xNN, quotes and backslashes escaped, cut at 60 bytes.
static void say_entry(int32_t k) { say_start(), say("metadata entry "), say_number(AS_INTEGER, k); }
static void say_quoted(const JsonEntry *e) {
  say("\"");
  for (int32_t i = 0; i < e->keyn && i < 60; ++i) {
    uint8_t c = e->key[i];
    if (c < 0x20 || c == 0x7f) {
      char x[5] = {'\\', 'x', "0123456789abcdef"[c >> 4], "0123456789abcdef"[c & 15], 0};
      say(x);
    } else {
      if (c == '"' || c == '\\') say("\\");
      say_bytes(&c, 1);
    }
  }
  say(e->keyn > 60 ? "...\"" : "\"");
}

static int same_key(const JsonEntry *a, const JsonEntry *b) {
  if (a->keyn != b->keyn) return 0;
  for (int32_t i = 0; i < a->keyn; ++i)
    if (a->key[i] != b->key[i]) return 0;
  return 1;
}

void validate_image(const JsonImage *image) {
  int32_t size[2] = {image->width, image->height}, nl = image->num_levels;
  message_prefix = 0;
  for (int k = 0; k < 2; ++k) {
    if (size[k] < 1) FAIL(V_NOT_POSITIVE, W_WIDTH + k, size[k]);
    if (size[k] > 65536) FAIL(V_OVER_LIMIT, W_WIDTH + k, size[k]);
  }
  if ((double)size[0] * size[1] > 1073741824.0) FAIL(V_IMAGE_SIZE, size[0], size[1]);
  if (!nl) FAIL(V_NO_LEVELS);
  for (int32_t l = 0; l < nl; ++l) check(&image->levels[l], image, l, -1);
  for (int32_t l = 0; l < nl; ++l) check_link(image, l);
  for (int32_t k = 0; k < image->num_objects; ++k) {
    const JsonObject *o = &image->objects[k];
    message_level = k, message_prefix = 2;
    if (o->level < 0 || o->level >= nl) FAIL(O_LEVEL, o->level, nl);
    if (!utf8(o->name, o->namen)) FAIL(O_NAME);
    if (o->mesh.parents.n || o->mesh.collapses.n) FAIL(O_RECORD);
    check(&o->mesh, image, 0, k);
    for (int32_t s = 0; s < o->strokes.n; ++s) {
      const JsonStroke *stroke = &o->strokes.items[s];
      check_stroke(stroke, s, k, nl);
      message_level = k, message_prefix = 2;
      if (stroke->level != o->level) FAIL(O_STROKE_LEVEL, s, stroke->level, o->level);
    }
  }
  for (int32_t s = 0; s < image->strokes.n; ++s) check_stroke(&image->strokes.items[s], s, -1, nl);
  // The metadata: each key and value UTF-8, each key once (an open-addressed table of entries).
  int32_t nm = image->num_metadata, slots = 16;
  while (slots < 2 * nm) slots *= 2;
  const JsonEntry **table = (const JsonEntry **)need(NEW(const JsonEntry *, slots));
  for (int32_t k = 0; k < nm; ++k) {
    const JsonEntry *e = &image->metadata[k];
    if (!utf8(e->key, e->keyn)) say_entry(k), say(": key is not valid UTF-8"), say_fail();
    if (!utf8(e->value, e->valuen)) say_entry(k), say(" ("), say_quoted(e), say("): value is not valid UTF-8"), say_fail();
    uint32_t h = 2166136261u;
    for (int32_t i = 0; i < e->keyn; ++i) h = (h ^ e->key[i]) * 16777619u;
    for (h &= (uint32_t)slots - 1; table[h]; h = (h + 1) & ((uint32_t)slots - 1))
      if (same_key(table[h], e)) say_entry(k), say(": key "), say_quoted(e), say(" appears twice"), say_fail();
    table[h] = e;
  }
}
