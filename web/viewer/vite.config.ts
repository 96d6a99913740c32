// The viewer as one minified ES module, dist/subvec-viewer.js, with fzstd bundled in: a static page
// loads it with one <script type="module">. Built from web/ with `npm run build:viewer`.
// Not Vite's library mode: that leaves ES output's whitespace unminified.
import { defineConfig } from 'vite';

const here = decodeURIComponent(new URL('.', import.meta.url).pathname);

// The shaders' text (render.ts) ships in the bundle: written readably there, minified here (the
// blanks around punctuation and between lines, and the zeros around a decimal point dropped).
const minifyShaders = {
  name: 'minify-shaders',
  transform(code: string, id: string) {
    if (!id.endsWith('/render.ts')) return null;
    return code.replace(/(_[VF]S = `)([^`]*)`/g, (_, start: string, body: string) =>
      start + body.replace(/\s*([-=+*/,;(){}<>?:])\s*/g, '$1').replace(/\s+/g, ' ').replace(/(\d\.)0+(?!\d)/g, '$1').replace(/(?<![\d.])0(\.\d)/g, '$1').trim() + '`');
  },
};

export default defineConfig({
  root: here,
  plugins: [minifyShaders],
  publicDir: false,
  build: {
    outDir: 'dist',
    emptyOutDir: true,
    target: 'es2022',
    sourcemap: false,
    modulePreload: false,
    rollupOptions: {
      input: here + 'src/index.ts',
      // keep the module's exports (an app build would drop them)
      preserveEntrySignatures: 'strict',
      output: {
        format: 'es',
        entryFileNames: 'subvec-viewer.js',
        inlineDynamicImports: true,
        banner: '/*! subvec-viewer (docs/viewer.md). Includes fzstd, (c) Arjun Barrett, MIT license. */',
      },
    },
  },
});
