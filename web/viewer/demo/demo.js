// The demo page: <subvec-image> plus a zoom slider, a level selector and a drop target. Plain
// JavaScript over the committed bundle, so any static file server serves it as it is.
import '../dist/subvec-viewer.js';

const $ = (id) => document.getElementById(id);
const image = $('image');
const zoom = $('zoom');
const level = $('level');
let name = 'rocket.svec';
let objectUrl = null;

// The slider is log2 of the zoom: 0 shows the whole image, 8 is 256x.
function showZoom() {
  const view = image.view;
  const z = view ? image.naturalWidth / (view.x1 - view.x0) : 1;
  zoom.value = String(Math.log2(Math.max(z, 1)));
  $('zoom-value').textContent = `${z < 10 ? z.toFixed(1) : Math.round(z)}×`;
}

// Zooms to z about the centre of what is shown now.
function setZoom(z) {
  const w = image.naturalWidth, h = image.naturalHeight;
  if (!w) return;
  const v = image.view ?? { x0: 0, y0: 0, x1: w, y1: h };
  const cx = (v.x0 + v.x1) / 2, cy = (v.y0 + v.y1) / 2;
  const hw = w / z / 2, hh = h / z / 2;
  image.setView(z <= 1 ? null : { x0: cx - hw, y0: cy - hh, x1: cx + hw, y1: cy + hh });
  showZoom();
}

zoom.addEventListener('input', () => setZoom(2 ** Number(zoom.value)));
$('zoom-in').addEventListener('click', () => setZoom(2 ** (Number(zoom.value) + 0.5)));
$('zoom-out').addEventListener('click', () => setZoom(2 ** (Number(zoom.value) - 0.5)));
$('fit').addEventListener('click', () => setZoom(1));
image.addEventListener('viewchange', showZoom);
level.addEventListener('change', () => { image.level = Number(level.value); });

image.addEventListener('load', (e) => {
  $('error').classList.remove('shown');
  const { width, height, levels } = e.detail;
  level.replaceChildren(...Array.from({ length: levels }, (_, i) => {
    const vertices = image.image.levels[i].positions.length / 2;
    return new Option(`${i}${i === 0 ? ' (finest)' : ''}: ${vertices} vertices`, String(i));
  }));
  level.value = String(image.level);
  $('status').dataset.file = `${name}: ${width} × ${height} pixels, ${levels} level${levels > 1 ? 's' : ''}`;
  $('status').textContent = $('status').dataset.file;
  showZoom();
});
image.addEventListener('render', (e) => {
  const s = e.detail;
  $('status').textContent = `${$('status').dataset.file ?? name} — drawn at depth ${s.depth}, ` +
    `${s.triangles} triangles, refine ${s.refineMs.toFixed(1)} ms, draw ${s.drawMs.toFixed(1)} ms`;
});
image.addEventListener('error', (e) => {
  // A dropped file's message names its object URL: name the file instead.
  const message = objectUrl ? e.detail.message.replace(objectUrl, name) : e.detail.message;
  $('error').textContent = message;
  $('error').classList.add('shown');
  $('status').textContent = '';
});

// A dropped or chosen file is shown through an object URL: the element loads it as any src.
function open(file) {
  if (!file) return;
  name = file.name;
  if (objectUrl) URL.revokeObjectURL(objectUrl);
  objectUrl = URL.createObjectURL(file);
  image.removeAttribute('level');
  image.setView(null);
  image.src = objectUrl;
}

$('file').addEventListener('change', (e) => open(e.target.files[0]));
const stage = $('stage');
stage.addEventListener('dragover', (e) => {
  e.preventDefault();
  stage.classList.add('over');
});
stage.addEventListener('dragleave', () => stage.classList.remove('over'));
stage.addEventListener('drop', (e) => {
  e.preventDefault();
  stage.classList.remove('over');
  open(e.dataTransfer.files[0]);
});
