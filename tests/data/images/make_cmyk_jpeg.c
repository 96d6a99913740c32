/* Writes cmyk.jpg: a 16 x 16 CMYK JPEG (Adobe APP14 marker, inverted samples as Photoshop and
 * most tools store them) of four flat 8 x 8 blocks, for tests/unit/io/image_io_test.cpp.
 * OpenCV cannot write CMYK JPEGs, so this file is committed; regenerate it with
 *   cc make_cmyk_jpeg.c -ljpeg -o /tmp/make_cmyk_jpeg && /tmp/make_cmyk_jpeg cmyk.jpg
 * (libjpeg62-turbo-dev). Blocks, as ink amounts C, M, Y, K in 0-255 and the RGB they stand for:
 *   top left     0, 255, 255,   0   red      (255, 0, 0)
 *   top right  255,   0, 255,   0   green    (0, 255, 0)
 *   bottom left 255, 255,  0,   0   blue     (0, 0, 255)
 *   bottom right  0,   0,   0, 128   gray     (127, 127, 127)
 */
#include <stdio.h>
#include <jpeglib.h>

int main(int argc, char** argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: %s OUT.jpg\n", argv[0]);
    return 2;
  }
  static const unsigned char ink[4][4] = {{0, 255, 255, 0}, {255, 0, 255, 0}, {255, 255, 0, 0}, {0, 0, 0, 128}};
  unsigned char rows[16][16 * 4];
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x)
      for (int k = 0; k < 4; ++k) rows[y][4 * x + k] = (unsigned char)(255 - ink[(y / 8) * 2 + x / 8][k]);

  FILE* out = fopen(argv[1], "wb");
  if (!out) return 1;
  struct jpeg_compress_struct c;
  struct jpeg_error_mgr err;
  c.err = jpeg_std_error(&err);
  jpeg_create_compress(&c);
  jpeg_stdio_dest(&c, out);
  c.image_width = 16;
  c.image_height = 16;
  c.input_components = 4;
  c.in_color_space = JCS_CMYK;
  jpeg_set_defaults(&c);  /* CMYK in, CMYK stored, Adobe marker written */
  jpeg_set_quality(&c, 95, TRUE);
  jpeg_start_compress(&c, TRUE);
  for (int y = 0; y < 16; ++y) {
    JSAMPROW row = rows[y];
    jpeg_write_scanlines(&c, &row, 1);
  }
  jpeg_finish_compress(&c);
  jpeg_destroy_compress(&c);
  return fclose(out) == 0 ? 0 : 1;
}
