// The subvec editor page: tools, view, and the conversation with `subvec serve` (docs/serve.md).
//
// State. The server owns the document, its version and its history; this page owns a session (its
// refined view of one level at the depth its zoom needs, for this browser tab: undo takes back
// this tab's edits only) and the last version it drew. Every request that
// changes the document or the session's view runs in one queue, one at a time, in the order the
// user asked (enqueue): each sends the version its predecessor left, so only another tab's edit
// can make a 409 conflict, and the page then reloads. A poll of /api/status notices changes made
// elsewhere the same way.

import { ApiError, Frame, decodeMoves, getJson, postFrame, postJson } from './api';
import { Renderer, Transform, softwareWebGL } from './gl';

type Tool = 'pan' | 'select' | 'drag' | 'move' | 'color' | 'points' | 'pen' | 'object';

const TOOL_HELP: Record<Tool, string> = {
  pan: 'Pan: drag to move the view. The wheel zooms at the cursor with every tool; the image is re-refined for the new zoom when you stop.',
  select: 'Select: click to see what the other tools would pick there — the nearest feature (pink, its control chain) or control vertex, and the color region a click would change (white points). Changes nothing.',
  drag: 'Drag (as-rigid-as-possible): press on a feature (or a vertex, with "vertex" picked) and drag. The part near where you grabbed follows the mouse (σ sets how far along the feature), and the whole mesh deforms as rigidly as possible around it; the image border stays in place.',
  move: 'Move feature: press near a feature and drag to translate the whole feature; hold Shift while dragging to rotate it about its center instead. The mesh around it follows as rigidly as possible.',
  points: 'Points: the control points, as handles. Click one to select it (Shift adds or removes), drag a box around several (Alt: draw a lasso; Shift adds), then drag any selected point or nudge with the arrow keys (Shift: 10 px) to move them; the mesh around follows as rigidly as possible ("region" sets how far). R recolors the selected points with the picked color. Esc clears the selection.',
  pen: 'Pen: press and drag to draw a new feature; on release it becomes a tear along the smooth curve (a C² B-spline) through what you drew, and the image does not change until you edit one side (Shift held on release: a crease, continuous color with a corner in it). End near where you started to close it. Where it crosses a feature, or ends within 2 px of one, the two meet at a junction. Delete removes the feature the Select tool picked.',
  object: 'Object: drag a rectangle round something to make it an object — the closed feature it frames, or what GrabCut finds in it — with its own mesh over a background completed under it. Press on an object and drag to move it; Shift+drag turns it and Alt+drag scales it about its centre. X hides the selected object or shows it again. Undo takes any of it back.',
  color: 'Color: click to recolor with the picked color; the white points show what a click changes. With "region" picked, the fill spreads from the click to the colors within "tolerance" of the clicked one, never across a tear (and within the radius, if capped); with "feature" or "vertex", the clicked side of the nearest one grown by the radius. BLEND mixes towards the color by "amount"; TRANSFORM maps the clicked color onto the new one and keeps the shading.',
};

const $ = <T extends HTMLElement = HTMLElement>(id: string) => document.getElementById(id) as T;
const canvas = $<HTMLCanvasElement>('canvas');
const statusBox = $('status');

interface LevelInfo { vertices: number; triangles: number; colors: number; features: number; mean_edge: number }
interface DocInfo {
  name: string; stem: string; version: number; width: number; height: number; levels: LevelInfo[];
  undo: number; redo: number; strokes: number; save_to: string | null;
  objects: { level: number; name: string; visible: boolean; vertices: number; strokes: number }[];
  filter: {
    available: boolean; bands: number; reason: string;
    current: null | { eta: number[]; geometry: boolean; color: boolean };
  };
}

const state = {
  doc: null as DocInfo | null,
  session: '',
  version: 0,
  level: 0,
  tool: 'drag' as Tool,
  view: { id: 0, depth: -1, partial: false, window: null as number[] | null, zoom: 0 },
  transform: { zoom: 1, panX: 0, panY: 0 } as Transform,
  overlays: { mesh: false, features: false },
  busy: 0,           // tasks queued or running (enqueue): never negative
  drag: null as Drag | null,  // the drag the pointer holds (its task may still be queued)
  pan: null as null | { x: number; y: number; panX: number; panY: number },
  fitted: true,      // the view is the fitted one: a resize fits again, until the user zooms or pans
  space: false,
  viewTimer: 0,
  measure: false,
  latencies: [] as number[],     // per measured drag preview: pointer event to frame drawn, ms
  phases: [] as number[][],      // per measured preview or click: [event to send, request, update, draw] ms
  clicks: [] as number[],        // per measured color click: click to frame drawn, ms
  control: new Float32Array(0),  // control positions of the level (image pixels), for the points tool
  selection: [] as number[],     // the points tool's selected control vertices
  // A box (or, with Alt, a lasso: the pointer's path) being drawn with the points tool.
  box: null as null | { pointer: number; from: [number, number]; to: [number, number]; add: boolean; lasso: [number, number][] | null },
  pen: null as null | { pointer: number; points: [number, number][] },  // a pen stroke (canvas pixels)
  picked: null as null | [number, number],  // where the Select tool last picked a feature
  // The view's objects (their GL vertex ranges, bottom to top), the one the object tool selected,
  // and a rectangle or a move it is drawing.
  objects: [] as { object: number; first: number; count: number }[],
  objectSel: -1,
  objectBox: null as null | { pointer: number; from: [number, number]; to: [number, number] },
  // A move, or with Shift a turn and with Alt a scaling, about the object's centre.
  objectMove: null as null | { pointer: number; object: number; first: number; count: number; start: [number, number];
    rest: Float32Array; d: [number, number]; mode: 'move' | 'rotate' | 'scale'; pivot: [number, number]; angle: number; scale: number },
  reload: false,  // an edit changed the level's topology: fetch the view and control mesh again
};

// A drag or move, from press to release. Its task (runDrag) holds the queue from the press
// until the end is committed; previews go out one at a time, the latest pointer position winning.
interface Drag {
  pointer: number;
  press: [number, number];   // canvas pixels
  moved: boolean;            // the pointer went CLICK_SLOP pixels from the press: a click is no drag
  start: [number, number];   // image pixels
  target: [number, number];
  rotate: number;
  shiftX: number;
  pending: boolean;          // a position not sent as a preview yet
  inFlight: Promise<void> | null;
  ok: boolean;               // the server took the start
  previewed: boolean;        // a preview was drawn
  released: boolean;
  release: (commit: boolean) => void;
  done: Promise<boolean>;    // true: released (commit), false: cancelled
  eventTime: number;
}
const CLICK_SLOP = 3;  // CSS pixels
const REGION_WHOLE = 400;  // the region slider's far right: the whole image

// σ and region as the sliders give them: "auto" at the far left (the server sizes them to what is
// grabbed: subvec::suggested_drag_extent), 0 (the whole image) at the region's far right.
function dragExtent(): { sigma: number | 'auto'; region: number | 'auto' } {
  const sigma = num('sigma'), region = num('region');
  return { sigma: sigma === 0 ? 'auto' : sigma, region: region === 0 ? 'auto' : region >= REGION_WHOLE ? 0 : region };
}

let renderer: Renderer;

// The queue: task after task, each started when the one before it settled.
let queue: Promise<void> = Promise.resolve();
function enqueue(task: () => Promise<void>): Promise<void> {
  state.busy++;
  const run = async () => {
    try {
      await task();
    } finally {
      state.busy--;
    }
  };
  const done = queue.then(run);
  queue = done.catch(() => undefined);
  return done;
}

// Refinement target: refined edges at most this many canvas pixels long, and MSAA. A GPU draws
// the fine setting for nothing; a software WebGL pays per triangle and per pixel, so it gets the
// coarse one (about a quarter of the triangles), and a drag previews a view of depth 2 or more one
// level coarser (the view's own limit points, a quarter of the triangles again; the release draws
// the view). ?quality=fine|coarse overrides the choice.
const quality = (() => {
  const asked = new URLSearchParams(location.search).get('quality');
  const software = softwareWebGL();
  const coarse = asked ? asked === 'coarse' : software;
  return { edge: coarse ? 8 : 3, antialias: !coarse, coarsePreview: coarse, software };
})();

function status(message: string, error = false) {
  statusBox.textContent = message;
  statusBox.classList.toggle('error', error);
}

function pick(): 'vertex' | 'feature' | 'region' {
  return (document.querySelector('input[name=pick]:checked') as HTMLInputElement).value as 'vertex' | 'feature' | 'region';
}
// Drags grab a vertex or a feature: "region" grabs the nearest feature.
const dragPick = () => (pick() === 'vertex' ? 'vertex' : 'feature');
const RADIUS_NONE = 201;  // the radius slider's far right: no cap
// What a color edit (or Select) takes: the pick, its radius (the image's diagonal for "no cap") and
// a region's tolerance.
function colorPick() {
  const select = pick(), r = num('radius');
  const radius = r >= RADIUS_NONE && state.doc ? Math.ceil(Math.hypot(state.doc.width, state.doc.height)) : r;
  return select === 'region' ? { select, radius, tolerance: num('tolerance') } : { select, radius };
}
function mode(): 'blend' | 'transform' {
  return (document.querySelector('input[name=mode]:checked') as HTMLInputElement).value as 'blend' | 'transform';
}
const num = (id: string) => Number($<HTMLInputElement>(id).value);

// ---- drawing -------------------------------------------------------------------------------

let frameRequested = false;
function redraw() {
  if (frameRequested || !renderer) return;
  frameRequested = true;
  requestAnimationFrame(() => {
    frameRequested = false;
    renderer.draw(state.transform, state.overlays);
  });
}

function resize() {
  const dpr = window.devicePixelRatio || 1;
  const w = Math.max(1, Math.round(canvas.clientWidth * dpr));
  const h = Math.max(1, Math.round(canvas.clientHeight * dpr));
  if (canvas.width !== w || canvas.height !== h) {
    canvas.width = w;
    canvas.height = h;
    renderer?.invalidate();
    if (state.fitted) fit();
    scheduleView();
  }
  redraw();
}

function fit() {
  if (!state.doc) return;
  const { width, height } = state.doc;
  const zoom = Math.min(canvas.width / width, canvas.height / height) * 0.96;
  state.transform = { zoom, panX: (canvas.width - width * zoom) / 2, panY: (canvas.height - height * zoom) / 2 };
  state.fitted = true;
  updateZoomLabel();
  scheduleView();
  redraw();
}

function updateZoomLabel() {
  $('zoom-out').textContent = `zoom ${(state.transform.zoom / (window.devicePixelRatio || 1)).toFixed(2)}×, ` +
    `depth ${state.view.depth < 0 ? '…' : state.view.depth}` +
    (quality.antialias ? '' : ' (software WebGL: coarser, no MSAA)');
}

// Canvas coordinates of a pointer event, and image coordinates of a canvas point.
function canvasPoint(e: MouseEvent): [number, number] {
  const r = canvas.getBoundingClientRect();
  const dpr = window.devicePixelRatio || 1;
  return [(e.clientX - r.left) * dpr, (e.clientY - r.top) * dpr];
}
function toImage([x, y]: [number, number]): [number, number] {
  const t = state.transform;
  return [(x - t.panX) / t.zoom, (y - t.panY) / t.zoom];
}

// ---- the refined view ----------------------------------------------------------------------

// The view the page asks for: the visible part of the image plus a quarter on each side, at the
// current zoom. The server plans it as the renderer does (subvec::view_mesh: the control faces
// whose limit surface may meet the window, refined until refined edges average at most
// quality.edge canvas pixels) and answers the depth it chose.
function wantedView(): { zoom: number; window: number[] } {
  const t = state.transform;
  const x0 = -t.panX / t.zoom, y0 = -t.panY / t.zoom;
  const x1 = (canvas.width - t.panX) / t.zoom, y1 = (canvas.height - t.panY) / t.zoom;
  const mx = (x1 - x0) * 0.25, my = (y1 - y0) * 0.25;
  return { zoom: t.zoom, window: [x0 - mx, y0 - my, x1 + mx, y1 + my] };
}

// Whether the view held is the one the server would plan now: the same zoom, and the screen inside
// its window (or every face refined). Otherwise the server is asked; it answers "unchanged" when
// the view held already covers the new one.
function viewCovers(want: { zoom: number; window: number[] }): boolean {
  if (want.zoom !== state.view.zoom) return false;
  if (!state.view.partial) return true;
  const have = state.view.window;
  if (!have) return false;
  const t = state.transform;
  const x0 = -t.panX / t.zoom, y0 = -t.panY / t.zoom;
  const x1 = (canvas.width - t.panX) / t.zoom, y1 = (canvas.height - t.panY) / t.zoom;
  return x0 >= have[0] && y0 >= have[1] && x1 <= have[2] && y1 <= have[3];
}

function scheduleView() {
  if (!state.doc || !state.session) return;
  clearTimeout(state.viewTimer);
  state.viewTimer = window.setTimeout(() => {
    if (state.drag || state.busy > 0) return scheduleView();
    if (!viewCovers(wantedView())) void loadView();
  }, 120);
}

// View loads go through the queue like edits: the server keeps one view per session and answers
// edits with deltas against it, so the page must always hold the view the server holds. A delta
// for another view makes the page load the view again. fetchView runs inside a task.
async function fetchView(): Promise<void> {
  const want = wantedView();
  const frame = await postFrame('/api/view', {
    session: state.session, level: state.level, window: want.window, scale: want.zoom,
    max_edge_pixels: quality.edge, have: state.view.id,
  });
  // "unchanged": the view held (`have`) already covers this one; nothing was sent.
  if (!frame.header.unchanged) {
    renderer.setMesh(frame.f32.positions, frame.u8.colors, frame.u32.triangles, frame.u32.coarse_triangles,
      frame.u32.tear_lines);
    renderer.setObjects(frame.f32.object_positions ?? new Float32Array(0), frame.u8.object_colors ?? new Uint8Array(0));
    state.objects = frame.header.objects ?? [];
  }
  state.view = {
    id: frame.header.view, depth: frame.header.depth, partial: frame.header.partial,
    window: want.window, zoom: want.zoom,
  };
  updateZoomLabel();
  redraw();
}
const loadView = () => enqueue(fetchView);

async function loadControl() {
  const c = await getJson(`/api/control?level=${state.level}`);
  state.control = new Float32Array(c.positions);
  renderer.setControl(state.control, new Uint32Array(c.edges));
  showPoints();
}

async function loadStrokes() {
  renderer.setStrokes(await getJson(`/api/strokes?level=${state.level}`));
}

function applyDelta(frame: Frame) {
  const h = frame.header;
  if (typeof h.version === 'number') state.version = h.version;
  if (h.reload) {
    // The topology changed (a feature added or deleted, or its undo): runEdit fetches it all.
    state.reload = true;
    return;
  }
  if (typeof h.offset_shift === 'number') {
    // A drag preview's moves, from the positions the page holds.
    if (h.view === state.view.id) {
      const m = decodeMoves(frame.u8.moved, frame.i16.offsets, h.offset_shift, renderer.positions);
      renderer.updatePositions(m.indices, m.values);
    }
    const m = decodeMoves(frame.u8.control_moved, frame.i16.control_offsets, h.offset_shift, state.control);
    const control = new Float32Array(state.control);
    m.indices.forEach((v, i) => control.set(m.values.subarray(2 * i, 2 * i + 2), 2 * v));
    state.control = control;
    renderer.setControl(control);
    return;
  }
  if (h.view === state.view.id) {
    renderer.updatePositions(h.dense_positions ? null : frame.u32.position_indices, frame.f32.positions);
    if (frame.u8.colors.length > 0 || h.dense_colors) {
      renderer.updateColors(h.dense_colors ? null : frame.u32.color_indices, frame.u8.colors);
    }
  } else if (h.view) {
    void loadView();
  }
  if (frame.f32.control.length > 0) {
    state.control = new Float32Array(frame.f32.control);
    renderer.setControl(state.control);
  }
  if (h.strokes_changed) void loadStrokes().then(redraw);
}

// ---- document ------------------------------------------------------------------------------

async function loadDocument() {
  const doc: DocInfo = await getJson(`/api/document?session=${state.session}`);
  state.doc = doc;
  state.version = doc.version;
  if (state.level >= doc.levels.length) state.level = 0;
  $('docname').textContent = `${doc.name} — ${doc.width}×${doc.height}`;
  const level = $<HTMLInputElement>('level');
  level.max = String(doc.levels.length - 1);
  level.value = String(state.level);
  level.disabled = doc.levels.length < 2;
  $('level-help').textContent = doc.levels.length < 2
    ? 'This file has one level. Levels of abstraction (a coarser image per level: subvec vectorize --levels) appear here when the file has them.'
    : `${doc.levels.length} levels: 0 is the finest, higher levels are coarser abstractions.`;
  describeLevel();
  buildFilterSliders(doc);
  $('save-help').textContent = doc.save_to
    ? `Save writes ${doc.save_to}. Downloads are made from the current state.`
    : 'Save downloads the .svec (start the server with -o OUT.svec to save in place).';
  updateHistoryButtons();
  showObjects(doc);
}

function describeLevel() {
  const doc = state.doc;
  if (!doc) return;
  const l = doc.levels[state.level];
  $('level-out').textContent = String(state.level);
  $('level').title = `level ${state.level}: ${l.vertices} control vertices, ${l.triangles} triangles, ${l.features} features`;
}

function updateHistoryButtons() {
  const doc = state.doc;
  $<HTMLButtonElement>('undo').disabled = !doc || doc.undo === 0;
  $<HTMLButtonElement>('redo').disabled = !doc || doc.redo === 0;
}

// Inside a task (or before the page takes input).
async function reloadAll(message?: string) {
  await loadDocument();
  await Promise.all([fetchView(), loadControl(), loadStrokes()]);
  renderer.setHighlight([], []);
  redraw();
  if (message) status(message);
}

async function refreshCounts() {
  const doc: DocInfo = await getJson(`/api/document?session=${state.session}`);
  if (state.doc) {
    state.doc.undo = doc.undo;
    state.doc.redo = doc.redo;
    state.doc.version = doc.version;
    state.doc.filter = doc.filter;
  }
  updateHistoryButtons();
  showFilter(doc);
  showObjects(doc);
}

// The Objects panel: the level's objects, top first, each with its visibility and its place in
// the drawing order.
function showObjects(doc: DocInfo) {
  const list = $('object-list');
  list.replaceChildren();
  const objects = (doc.objects ?? []).map((o, i) => ({ ...o, index: i })).filter((o) => o.level === state.level);
  $('objects-empty').hidden = objects.length > 0;
  const count = (doc.objects ?? []).length;
  for (const o of objects.reverse()) {
    const li = document.createElement('li');
    li.dataset.object = String(o.index);
    li.classList.toggle('selected', o.index === state.objectSel);
    const shown = document.createElement('input');
    shown.type = 'checkbox';
    shown.checked = o.visible;
    shown.title = 'shown';
    shown.addEventListener('change', () => void objectEdit('/api/object/visible', { object: o.index, visible: shown.checked }));
    const label = document.createElement('span');
    label.textContent = `${o.name || 'object ' + o.index} (${o.vertices} vertices${o.strokes ? `, ${o.strokes} strokes` : ''})`;
    label.addEventListener('click', () => { state.objectSel = o.index; showObjects(doc); status(`object ${o.index} selected`); });
    const up = document.createElement('button');
    up.textContent = '▲';
    up.title = 'raise';
    up.disabled = o.index + 1 >= count;
    up.addEventListener('click', () => void objectEdit('/api/object/order', { object: o.index, to: o.index + 1 }));
    const down = document.createElement('button');
    down.textContent = '▼';
    down.title = 'lower';
    down.disabled = o.index === 0;
    down.addEventListener('click', () => void objectEdit('/api/object/order', { object: o.index, to: o.index - 1 }));
    li.append(shown, label, up, down);
    list.append(li);
  }
}
async function objectEdit(url: string, body: Record<string, unknown>) {
  await edit(async () => {
    const f = await postFrame(url, { session: state.session, version: state.version, level: state.level, ...body });
    applyDelta(f);
    status(f.header.log);
  });
}

// Runs an edit inside a task: on a version conflict (another tab's edit) reloads from the server,
// on other errors reports them.
// `run` returns true when it drew the result itself: no second frame then.
async function runEdit(run: () => Promise<void | boolean>) {
  let drawn = false;
  try {
    drawn = (await run()) === true;
    if (state.reload) {
      state.reload = false;
      drawn = false;
      await loadDocument();
      await Promise.all([fetchView(), loadControl(), loadStrokes()]);
    }
    await refreshCounts();
  } catch (e) {
    drawn = false;
    await reportError(e);
  } finally {
    if (!drawn) redraw();
  }
}
const edit = (run: () => Promise<void | boolean>) => enqueue(() => runEdit(run));

async function reportError(e: unknown) {
  if (e instanceof ApiError && e.status === 409 && /document changed in another tab/.test(e.message)) {
    await reloadAll();
    status('the document changed in another tab: reloaded it, try again', true);
  } else if (e instanceof ApiError && e.status === 404 && /session/.test(e.message)) {
    await startSession();
    status('the session had expired: reloaded', true);
  } else {
    status(e instanceof Error ? e.message : String(e), true);
  }
}

// ---- tools ---------------------------------------------------------------------------------

function setTool(tool: Tool) {
  state.tool = tool;
  document.querySelectorAll<HTMLButtonElement>('#tools button').forEach((b) =>
    b.classList.toggle('active', b.dataset.tool === tool));
  $('tool-help').textContent = TOOL_HELP[tool];
  canvas.classList.toggle('pan', tool === 'pan');
  if (!renderer) return;  // at start, before the renderer
  renderer.setHighlight([], []);
  showPoints();
  redraw();
}

// ---- the points tool: control points as direct handles --------------------------------------

const POINT_HIT = 6;  // CSS pixels: a press this close to a point takes it
function showPoints() {
  renderer.setPoints(state.tool === 'points', state.selection);
  $<HTMLButtonElement>('recolor-points').disabled = state.selection.length === 0;
}
function selectionLine() {
  const n = state.selection.length;
  return n ? `${n} control point${n === 1 ? '' : 's'} selected: drag one or use the arrow keys to move them` : 'no control point selected';
}
function setSelection(vertices: number[]) {
  state.selection = [...new Set(vertices)].sort((a, b) => a - b);
  showPoints();
  redraw();
}
// The control point nearest to canvas point p within POINT_HIT CSS px, or -1.
function pointAt(p: [number, number]): number {
  const t = state.transform, dpr = window.devicePixelRatio || 1;
  let best = -1, bestD = POINT_HIT * dpr;
  for (let i = 0; i < state.control.length / 2; i++) {
    const d = Math.hypot(state.control[2 * i] * t.zoom + t.panX - p[0], state.control[2 * i + 1] * t.zoom + t.panY - p[1]);
    if (d <= bestD) bestD = d, best = i;
  }
  return best;
}
function pointsDown(e: PointerEvent) {
  const p = canvasPoint(e);
  const hit = pointAt(p);
  if (hit >= 0 && state.selection.includes(hit) && !e.shiftKey) {
    void dragStart(e);  // a press on the selection moves it
    return;
  }
  if (hit >= 0) {
    const s = state.selection;
    setSelection(e.shiftKey ? (s.includes(hit) ? s.filter((v) => v !== hit) : [...s, hit]) : [hit]);
    status(selectionLine());
    if (!e.shiftKey) void dragStart(e);  // and a drag right away moves it
    return;
  }
  state.box = { pointer: e.pointerId, from: p, to: p, add: e.shiftKey, lasso: e.altKey ? [p] : null };
  canvas.setPointerCapture(e.pointerId);
  drawBox();
}
function drawBox() {
  const box = $('box'), b = state.box, lasso = document.getElementById('lasso') as unknown as SVGSVGElement;
  box.hidden = !b || !!b.lasso;
  lasso.style.display = b && b.lasso ? 'block' : 'none';
  if (!b) return;
  const dpr = window.devicePixelRatio || 1;
  if (b.lasso) {
    lasso.querySelector('polygon')!.setAttribute('points', b.lasso.map(([x, y]) => `${x / dpr},${y / dpr}`).join(' '));
    return;
  }
  const [x0, x1] = [b.from[0], b.to[0]].sort((a, c) => a - c), [y0, y1] = [b.from[1], b.to[1]].sort((a, c) => a - c);
  Object.assign(box.style, { left: `${x0 / dpr}px`, top: `${y0 / dpr}px`, width: `${(x1 - x0) / dpr}px`, height: `${(y1 - y0) / dpr}px` });
}
function boxEnd(e: PointerEvent | null, cancel = false) {
  const b = state.box;
  if (!b || (e && e.pointerId !== b.pointer)) return;
  if (e) b.to = canvasPoint(e);
  state.box = null;
  drawBox();
  if (cancel) return;
  const t = state.transform;
  const [x0, x1] = [b.from[0], b.to[0]].sort((a, c) => a - c), [y0, y1] = [b.from[1], b.to[1]].sort((a, c) => a - c);
  // Inside the lasso: an even number of its edges cross the ray to the right (the polygon closes
  // back to its first point).
  const inLasso = (x: number, y: number, path: [number, number][]) => {
    let inside = false;
    for (let i = 0, j = path.length - 1; i < path.length; j = i++) {
      const [xi, yi] = path[i], [xj, yj] = path[j];
      if ((yi > y) !== (yj > y) && x < ((xj - xi) * (y - yi)) / (yj - yi) + xi) inside = !inside;
    }
    return inside;
  };
  const inside: number[] = [];
  for (let i = 0; i < state.control.length / 2; i++) {
    const x = state.control[2 * i] * t.zoom + t.panX, y = state.control[2 * i + 1] * t.zoom + t.panY;
    if (b.lasso ? inLasso(x, y, b.lasso) : x >= x0 && x <= x1 && y >= y0 && y <= y1) inside.push(i);
  }
  setSelection(b.add ? [...state.selection, ...inside] : inside);
  status(selectionLine());
}
// An arrow-key nudge of the selection: one edit each, queued.
function nudge(dx: number, dy: number) {
  if (!state.selection.length) {
    status('select control points first: click one, or drag a box around several');
    return;
  }
  const vertices = state.selection.slice(), level = state.level;
  const region = dragExtent().region;
  void edit(async () => {
    const f = await postFrame('/api/points/move', {
      session: state.session, version: state.version, level, vertices, translate: [dx, dy], region,
    });
    applyDelta(f);
    status(f.header.log);
  });
}
// Color per control point: the selection's color values take the picked color.
function recolorPoints() {
  if (!state.selection.length) {
    status('select control points first (the points tool, P)');
    return;
  }
  const vertices = state.selection.slice(), level = state.level;
  void edit(async () => {
    const f = await postFrame('/api/color', {
      session: state.session, version: state.version, level, select: 'vertices', vertices,
      mode: mode(), color: hexColor(), amount: num('amount'),
    });
    applyDelta(f);
    status(f.header.log);
  });
}

// Select changes nothing, so it skips the queue; of quick clicks, the last one's answer shows.
let selectSeq = 0;
async function doSelect(at: [number, number]) {
  const seq = ++selectSeq;
  try {
    const r = await postJson('/api/select', { level: state.level, at, ...colorPick() });
    if (seq !== selectSeq) return;
    renderer.setHighlight(r.chain, r.region);
    state.picked = r.feature >= 0 ? at : null;
    const what = r.feature >= 0 ? `the nearest feature, ${r.distance.toFixed(1)} px away (pink)`
      : r.vertex >= 0 ? `the nearest control point, ${r.distance.toFixed(1)} px away` : 'the region around the click';
    status(`${what}; a color edit here changes the ${r.colors} control colors shown white` +
      (r.feature >= 0 ? '; Delete deletes the feature' : ''));
  } catch (e) {
    if (seq === selectSeq) status(e instanceof Error ? e.message : String(e), true);
  }
  redraw();
}

// The new color: the picker, a typed #rrggbb or "r, g, b", and the eyedropper all set it.
function setColor(rgb: number[]) {
  const hex = '#' + rgb.map((v) => Math.round(v).toString(16).padStart(2, '0')).join('');
  $<HTMLInputElement>('color').value = hex;
  $<HTMLInputElement>('color-text').value = hex;
  $('color-text').classList.remove('bad');
}
function parseColor(text: string): number[] | null {
  const t = text.trim();
  const hex = /^#?([0-9a-f]{6})$/i.exec(t);
  if (hex) return [0, 2, 4].map((i) => parseInt(hex[1].slice(i, i + 2), 16));
  const parts = t.replace(/^rgb\(|\)$/gi, '').split(/[\s,]+/).filter(Boolean).map(Number);
  return parts.length === 3 && parts.every((v) => Number.isFinite(v) && v >= 0 && v <= 255) ? parts : null;
}
// The eyedropper: the drawn color under the mouse.
let mouseAt: [number, number] | null = null;
function eyedropper() {
  if (!mouseAt) {
    status('point at the image and press I to take its color');
    return;
  }
  renderer.draw(state.transform, state.overlays);
  const [r, g, b] = renderer.readPixel(mouseAt[0], mouseAt[1]);
  setColor([r, g, b]);
  status(`picked the color (${r}, ${g}, ${b})`);
}

// The color tool's preview: the region a click would change, shown as the mouse moves (one request
// in flight; the latest position wins).
let previewWanted: [number, number] | null = null;
let previewBusy = false;
let previewEpoch = 0;  // a click starts a new one: an answer from before it is stale
function previewRegion(at: [number, number]) {
  previewWanted = at;
  if (previewBusy) return;
  previewBusy = true;
  void (async () => {
    try {
      while (previewWanted) {
        const p = previewWanted, epoch = previewEpoch;
        previewWanted = null;
        const r = await postJson('/api/select', { level: state.level, at: p, ...colorPick() });
        if (state.tool !== 'color' || state.drag) break;
        if (epoch !== previewEpoch) continue;  // a click came first: nothing to draw for this
        renderer.setHighlight([], r.region);
        status(`a click here changes the ${r.colors} control colors shown white`);
        redraw();
      }
    } catch {
      // outside the image or no feature: no preview
    } finally {
      previewBusy = false;
    }
  })();
}

function hexColor(): number[] {
  const v = $<HTMLInputElement>('color').value;
  return [1, 3, 5].map((i) => parseInt(v.slice(i, i + 2), 16));
}

async function doColor(at: [number, number], eventTime = performance.now()) {
  previewEpoch++;
  previewWanted = null;
  await edit(async () => {
    const sent = performance.now();
    const f = await postFrame('/api/color', {
      session: state.session, version: state.version, level: state.level, at, ...colorPick(),
      mode: mode(), color: hexColor(), amount: num('amount'),
    });
    const answered = performance.now();
    applyDelta(f);
    renderer.setHighlight([], []);  // the result unobstructed; the next move previews again
    const updated = performance.now();
    // Drawn now, not at the next animation frame after the history counts come back.
    renderer.draw(state.transform, state.overlays);
    if (state.measure) {
      renderer.readPixel(0, 0);  // waits until the frame is drawn
      state.clicks.push(performance.now() - eventTime);
      state.phases.push([sent - eventTime, answered - sent, updated - answered, performance.now() - updated]);
    }
    status(f.header.log);
    return true;  // drawn
  });
}

// The object selected in the Objects panel or with the object tool, when it is on the level shown:
// Stylize and Filter then act on it alone (null: on the level).
function selectedObject(): number | null {
  const o = state.doc?.objects?.[state.objectSel];
  return o && o.level === state.level ? state.objectSel : null;
}

function onWhat(object: number | null) {
  return object === null ? '' : ` (object ${object})`;
}

async function doStylize() {
  await edit(async () => {
    const threshold = $<HTMLInputElement>('threshold').value;
    const object = selectedObject();
    const f = await postFrame('/api/stylize', {
      session: state.session, version: state.version, level: state.level, object,
      threshold: threshold === '' ? null : Number(threshold), seed: num('seed'), probability: num('probability'),
    });
    applyDelta(f);
    status(`stylize${onWhat(object)}: ${f.header.log}`);
  });
}

// ---- filter (the level pyramid, paper §6.4) ---------------------------------------------------

// One η slider per detail band, finest first. The sliders are absolute: the server filters the
// image the current run of filter changes started from, and any other change (an edit, undo, redo,
// another tab) starts a new run, so the sliders go back to 1 (showFilter).
function buildFilterSliders(doc: DocInfo) {
  const box = $('filter-bands');
  box.textContent = '';
  for (let b = 0; b < doc.filter.bands; b++) {
    const row = document.createElement('div');
    row.className = 'row';
    const label = document.createElement('label');
    label.htmlFor = `eta-${b}`;
    label.textContent = `η band ${b + 1}`;
    label.title = b === 0 ? 'the finest band: level 0 against level 1' : `level ${b} against level ${b + 1}`;
    const input = document.createElement('input');
    Object.assign(input, { type: 'range', id: `eta-${b}`, min: '0', max: '2', step: '0.05', value: '1' });
    const out = document.createElement('output');
    out.id = `eta-${b}-out`;
    input.addEventListener('input', () => { out.textContent = Number(input.value).toFixed(2); });
    input.addEventListener('change', () => void doFilter());
    row.append(label, input, out);
    box.append(row);
  }
  const enabled = doc.filter.available;
  for (const id of ['filter-geometry', 'filter-color', 'filter-reset']) $<HTMLInputElement>(id).disabled = !enabled;
  $('filter-note').textContent = enabled
    ? `Smooths or enhances the image through its level pyramid (${doc.filter.bands} detail ` +
      `${doc.filter.bands === 1 ? 'band' : 'bands'} between its ${doc.levels.length} levels): η < 1 ` +
      'removes detail (1 = unchanged, 0 = the coarser level\'s shape or colors), η > 1 sharpens it. ' +
      'Release a slider to apply it to every level; each change is one undo step.'
    : `Smooths or enhances the image through its level pyramid. Not available here: ${doc.filter.reason}.`;
  showFilter(doc);
}

function showFilter(doc: DocInfo) {
  const cur = doc.filter.current;
  for (let b = 0; b < doc.filter.bands; b++) {
    const input = document.getElementById(`eta-${b}`) as HTMLInputElement | null;
    if (!input) continue;
    const eta = cur ? cur.eta[Math.min(b, cur.eta.length - 1)] : 1;
    input.value = String(eta);
    $(`eta-${b}-out`).textContent = eta.toFixed(2);
  }
  if (cur) {
    $<HTMLInputElement>('filter-geometry').checked = cur.geometry;
    $<HTMLInputElement>('filter-color').checked = cur.color;
  }
}

async function doFilter(reset = false) {
  const doc = state.doc;
  if (!doc || !doc.filter.available) return;
  const eta: number[] = [];
  for (let b = 0; b < doc.filter.bands; b++) {
    if (reset) $<HTMLInputElement>(`eta-${b}`).value = '1';
    eta.push(num(`eta-${b}`));
  }
  // Nothing to do (and no undo step to make) when no filter is shown and every η is 1.
  if (!doc.filter.current && eta.every((e) => e === 1)) return;
  const geometry = $<HTMLInputElement>('filter-geometry').checked;
  const color = $<HTMLInputElement>('filter-color').checked;
  await edit(async () => {
    const object = selectedObject();
    const f = await postFrame('/api/filter', { session: state.session, version: state.version, eta, geometry, color, object });
    applyDelta(f);
    status(`filter${onWhat(object)}: ${f.header.log}`);
  });
}

// Quick presses queue up; those past the end of the history say so instead of asking.
async function doHistory(kind: 'undo' | 'redo') {
  await edit(async () => {
    if (state.doc && state.doc[kind] === 0) {
      status(`nothing to ${kind}`);
      return;
    }
    const f = await postFrame(`/api/${kind}`, { session: state.session, version: state.version });
    applyDelta(f);
    renderer.setHighlight([], []);
    status(f.header.log ? `${kind === 'undo' ? 'undid' : 'redid'}: ${f.header.log}` : kind === 'undo' ? 'undone' : 'redone');
  });
}

// A download with a progress line: the server prepares the file (a PDF or SVG export takes a
// moment), the page shows what arrives, then hands the bytes to the browser as a file. It reads the
// document and changes nothing, so it does not wait in the queue.
const FORMAT_NAMES: Record<string, string> = { svec: '.svec', 'svec.json': '.svec.json', png: 'PNG', pdf: 'PDF', svg: 'SVG' };
let downloads = 0;
async function download(format: string) {
  const what = FORMAT_NAMES[format] ?? format;
  const mb = (n: number) => (n / 1e6).toFixed(n < 1e7 ? 1 : 0);
  downloads++;
  status(`preparing the ${what}…`);
  try {
    const response = await fetch(`/api/download?format=${format}&level=${state.level}`, { cache: 'no-store' });
    if (!response.ok || !response.body) {
      let message = `${response.status} ${response.statusText}`;
      try {
        message = (await response.json()).error ?? message;
      } catch {
        // not JSON: the status line
      }
      throw new Error(`download failed: ${message}`);
    }
    const total = Number(response.headers.get('X-Decoded-Length')) || 0;
    const name = /filename="([^"]+)"/.exec(response.headers.get('Content-Disposition') ?? '')?.[1] ?? `image.${format}`;
    const reader = response.body.getReader();
    const chunks: Uint8Array<ArrayBuffer>[] = [];
    let received = 0;
    let shown = 0;
    for (;;) {
      const { done, value } = await reader.read();
      if (done) break;
      chunks.push(value);
      received += value.length;
      if (performance.now() - shown > 100) {
        shown = performance.now();
        status(`downloading the ${what}: ${mb(received)}${total ? ` of ${mb(total)}` : ''} MB`);
      }
    }
    const url = URL.createObjectURL(new Blob(chunks, { type: response.headers.get('Content-Type') ?? '' }));
    const a = document.createElement('a');
    a.href = url;
    a.download = name;
    document.body.appendChild(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(url), 60000);
    status(`downloaded ${name} (${mb(received)} MB)`);
  } catch (e) {
    status(e instanceof Error ? e.message : String(e), true);
  } finally {
    downloads--;
  }
}

async function doSave() {
  if (!state.doc?.save_to) {
    await download('svec');
    return;
  }
  await edit(async () => {
    const r = await postJson('/api/save', { version: state.version });
    status(`saved ${r.saved}`);
  });
}

async function setLevel(level: number) {
  if (!state.doc || level < 0 || level >= state.doc.levels.length || level === state.level) return;
  state.level = level;
  state.selection = [];  // a level's own vertices
  $<HTMLInputElement>('level').value = String(level);
  describeLevel();
  renderer.setHighlight([], []);
  await enqueue(() => Promise.all([fetchView(), loadControl(), loadStrokes()]).then(() => undefined));
  status(`level ${level}`);
}

// Drag and move. The press queues the drag's task (runDrag), which picks the handle on the
// server (and factors the ARAP system), sends previews while the pointer moves (one in flight; the
// latest position wins) and, on release, commits the end; a release the server refuses commits
// the last position the preview took. A press released without moving is a click: nothing is
// sent (or the started drag is cancelled), and no undo step is made.
function dragStart(e: PointerEvent) {
  const p = canvasPoint(e);
  const at = toImage(p);
  let release!: (commit: boolean) => void;
  const done = new Promise<boolean>((r) => { release = r; });
  const drag: Drag = {
    pointer: e.pointerId, press: p, moved: false, start: at, target: at, rotate: 0, shiftX: p[0],
    pending: false, inFlight: null, ok: false, previewed: false, released: false, release, done,
    eventTime: 0,
  };
  state.drag = drag;
  canvas.setPointerCapture(e.pointerId);
  void enqueue(() => runDrag(drag));
}

async function runDrag(drag: Drag) {
  if (drag.released && !drag.moved) return;  // a click, released before its turn came
  try {
    const points = state.tool === 'points';
    const r = await postJson('/api/drag/start', {
      session: state.session, version: state.version, level: state.level, tool: state.tool,
      select: state.tool === 'move' ? 'feature' : dragPick(), at: drag.start, ...dragExtent(),
      ...(points ? { vertices: state.selection } : {}),
    });
    renderer.setHighlight(r.chain, r.vertex >= 0 ? [r.vertex] : []);
    drag.ok = true;
    const n = state.selection.length;
    status(`dragging ${points ? `${n} control point${n === 1 ? '' : 's'}` : r.feature >= 0 ? 'a feature' : 'a control point'}; ` +
      (r.region > 0 ? `the image follows within ${Math.round(r.region)} px` : 'the whole image follows'));
  } catch (e) {
    if (state.drag === drag) state.drag = null;
    await reportError(e);
    return;
  }
  pump(drag);
  const commit = await drag.done;
  while (drag.inFlight) await drag.inFlight;
  renderer.coarsePreview(false);
  if (!commit || !drag.moved) {
    try {
      await postJson('/api/drag/cancel', { session: state.session });
      if (drag.previewed) await Promise.all([fetchView(), loadControl()]);
      status(!commit ? 'drag cancelled' : state.tool === 'points' ? selectionLine() : 'a click: press and drag to move');
    } catch (e) {
      await reportError(e);
    }
    redraw();
    return;
  }
  await runEdit(async () => {
    let f: Frame;
    try {
      f = await postFrame('/api/drag/end', {
        session: state.session, version: state.version, to: drag.target, rotate: drag.rotate,
      });
    } catch (e) {
      // Refused: the document did not change, so drop the preview.
      await Promise.all([fetchView(), loadControl()]);
      throw e;
    }
    applyDelta(f);
    status(f.header.log);
    if (state.view.partial) await fetchView();
  });
}

function pump(drag: Drag) {
  if (!drag.ok || drag.inFlight || !drag.pending || drag.released) return;
  drag.pending = false;
  const eventTime = drag.eventTime;
  const sent = performance.now();
  drag.inFlight = (async () => {
    try {
      const f = await postFrame('/api/drag/move', { session: state.session, to: drag.target, rotate: drag.rotate });
      const answered = performance.now();
      applyDelta(f);
      if (quality.coarsePreview && state.view.depth >= 2) renderer.coarsePreview(true);
      const updated = performance.now();
      drag.previewed = true;
      renderer.draw(state.transform, state.overlays);
      if (state.measure) {
        renderer.readPixel(0, 0);  // waits until the frame is drawn
        const drawn = performance.now();
        state.latencies.push(drawn - eventTime);
        // Where the time went: the event to its handler, the request, the update, the draw.
        state.phases.push([sent - eventTime, answered - sent, updated - answered, drawn - updated]);
      }
      status('dragging');
    } catch (e) {
      // A preview the mesh cannot take: keep the last good one, say why in plain words.
      status(e instanceof ApiError && e.status === 422
        ? 'the mesh cannot follow further: release to keep the last position it took'
        : e instanceof Error ? e.message : String(e), true);
    } finally {
      drag.inFlight = null;
      pump(drag);
    }
  })();
}

// The pointer's position into the drag (not sent).
function track(drag: Drag, e: PointerEvent) {
  const p = canvasPoint(e);
  const dpr = window.devicePixelRatio || 1;
  if (!drag.moved && Math.hypot(p[0] - drag.press[0], p[1] - drag.press[1]) < CLICK_SLOP * dpr) return;
  drag.moved = true;
  if (state.tool === 'move' && e.shiftKey) {
    drag.rotate = (p[0] - drag.shiftX) * 0.5;
  } else {
    drag.target = toImage(p);
    drag.shiftX = p[0] - drag.rotate * 2;
  }
  drag.pending = true;
  drag.eventTime = e.timeStamp || performance.now();
}

function dragMove(e: PointerEvent) {
  const drag = state.drag;
  if (!drag || e.pointerId !== drag.pointer) return;
  track(drag, e);
  pump(drag);
}

// Release (commit) or cancel: the pointer is free at once; the drag's task finishes in the queue.
function dragEnd(e: PointerEvent | null, cancel = false) {
  const drag = state.drag;
  if (!drag || (e && e.pointerId !== drag.pointer)) return;
  if (e && !cancel) track(drag, e);
  state.drag = null;
  drag.released = true;
  drag.release(!cancel);
}

// The pen: the pointer's path, drawn over the canvas while it moves; on release, one edit that
// adds the feature (the server fits the curve). A press released without moving draws nothing.
function penDown(e: PointerEvent) {
  state.pen = { pointer: e.pointerId, points: [canvasPoint(e)] };
  canvas.setPointerCapture(e.pointerId);
  drawPen();
}
function penMove(e: PointerEvent) {
  const pen = state.pen;
  if (!pen || e.pointerId !== pen.pointer) return;
  const p = canvasPoint(e), last = pen.points[pen.points.length - 1];
  const dpr = window.devicePixelRatio || 1;
  if (Math.hypot(p[0] - last[0], p[1] - last[1]) < 2 * dpr) return;
  pen.points.push(p);
  drawPen();
}
function drawPen() {
  const svg = $('pen-path'), pen = state.pen;
  svg.style.display = pen ? 'block' : 'none';
  if (!pen) return;
  const dpr = window.devicePixelRatio || 1;
  svg.querySelector('polyline')!.setAttribute('points', pen.points.map(([x, y]) => `${x / dpr},${y / dpr}`).join(' '));
}
function penEnd(e: PointerEvent | null, cancel = false) {
  const pen = state.pen;
  if (!pen || (e && e.pointerId !== pen.pointer)) return;
  if (e && !cancel) penMove(e);
  state.pen = null;
  drawPen();
  if (cancel) { status('pen stroke cancelled'); return; }
  if (!state.doc) return;
  const { width, height } = state.doc;
  const points = pen.points.map((p) => {
    const [x, y] = toImage(p);
    return [Math.min(Math.max(x, 0), width), Math.min(Math.max(y, 0), height)];
  });
  let length = 0;
  for (let i = 1; i < points.length; i++) length += Math.hypot(points[i][0] - points[i - 1][0], points[i][1] - points[i - 1][1]);
  if (points.length < 2 || length < 2) { status('a click: press and drag to draw a feature'); return; }
  const kind = e?.shiftKey ? 'crease' : 'tear';
  void edit(async () => {
    const f = await postFrame('/api/feature/add', {
      session: state.session, version: state.version, level: state.level, points, kind,
    });
    applyDelta(f);
    state.picked = null;
    status(f.header.log);
  });
}
async function deletePicked() {
  const at = state.picked;
  if (!at) { status('pick a feature with the Select tool first (V), then press Delete'); return; }
  state.picked = null;
  await edit(async () => {
    const f = await postFrame('/api/feature/delete', { session: state.session, version: state.version, level: state.level, at });
    applyDelta(f);
    renderer.setHighlight([], []);
    status(f.header.log);
  });
}

// ---- the object tool (issue 26) ----------------------------------------------------------------

// The topmost object of the view under image point p, or null.
function objectAt(p: [number, number]) {
  const q = renderer.objectPositions;
  for (let i = state.objects.length - 1; i >= 0; --i) {
    const o = state.objects[i];
    for (let g = o.first; g < o.first + o.count; g += 3) {
      const ax = q[2 * g], ay = q[2 * g + 1], bx = q[2 * g + 2], by = q[2 * g + 3], cx = q[2 * g + 4], cy = q[2 * g + 5];
      const d1 = (bx - ax) * (p[1] - ay) - (by - ay) * (p[0] - ax);
      const d2 = (cx - bx) * (p[1] - by) - (cy - by) * (p[0] - bx);
      const d3 = (ax - cx) * (p[1] - cy) - (ay - cy) * (p[0] - cx);
      if ((d1 >= 0 && d2 >= 0 && d3 >= 0) || (d1 <= 0 && d2 <= 0 && d3 <= 0)) return o;
    }
  }
  return null;
}
function objectDown(e: PointerEvent) {
  const at = toImage(canvasPoint(e));
  const o = objectAt(at);
  canvas.setPointerCapture(e.pointerId);
  if (o) {
    // The pivot of a turn or a scaling: the centre of the object's drawn bounding box.
    const q = renderer.objectPositions;
    let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
    for (let g = o.first; g < o.first + o.count; ++g) {
      x0 = Math.min(x0, q[2 * g]); x1 = Math.max(x1, q[2 * g]);
      y0 = Math.min(y0, q[2 * g + 1]); y1 = Math.max(y1, q[2 * g + 1]);
    }
    state.objectSel = o.object;
    state.objectMove = { pointer: e.pointerId, object: o.object, first: o.first, count: o.count, start: at,
      rest: new Float32Array(q), d: [0, 0], mode: e.shiftKey ? 'rotate' : e.altKey ? 'scale' : 'move',
      pivot: [(x0 + x1) / 2, (y0 + y1) / 2], angle: 0, scale: 1 };
    status(`object ${o.object} selected: drag to move it (Shift: turn, Alt: scale), X hides it`);
    return;
  }
  state.objectBox = { pointer: e.pointerId, from: canvasPoint(e), to: canvasPoint(e) };
  drawObjectBox();
}
function objectMoveTo(e: PointerEvent) {
  const m = state.objectMove;
  if (m && e.pointerId === m.pointer) {
    const at = toImage(canvasPoint(e));
    const [px, py] = m.pivot;
    if (m.mode === 'move') {
      m.d = [at[0] - m.start[0], at[1] - m.start[1]];
    } else if (m.mode === 'rotate') {
      m.angle = ((Math.atan2(at[1] - py, at[0] - px) - Math.atan2(m.start[1] - py, m.start[0] - px)) * 180) / Math.PI;
    } else {
      const r0 = Math.hypot(m.start[0] - px, m.start[1] - py), r1 = Math.hypot(at[0] - px, at[1] - py);
      m.scale = r0 > 1 ? Math.min(20, Math.max(0.05, r1 / r0)) : 1;
    }
    renderer.offsetObject(m.rest, m.first, m.count, m.d[0], m.d[1], m.pivot, m.angle, m.scale);
    redraw();
    return true;
  }
  const b = state.objectBox;
  if (b && e.pointerId === b.pointer) {
    b.to = canvasPoint(e);
    drawObjectBox();
    return true;
  }
  return false;
}
function drawObjectBox() {
  const box = $('box'), b = state.objectBox;
  box.hidden = !b;
  if (!b) return;
  const dpr = window.devicePixelRatio || 1;
  const [x0, x1] = [b.from[0], b.to[0]].sort((a, c) => a - c), [y0, y1] = [b.from[1], b.to[1]].sort((a, c) => a - c);
  Object.assign(box.style, { left: `${x0 / dpr}px`, top: `${y0 / dpr}px`, width: `${(x1 - x0) / dpr}px`, height: `${(y1 - y0) / dpr}px` });
}
function objectEnd(e: PointerEvent | null, cancel = false) {
  const m = state.objectMove;
  if (m && (!e || e.pointerId === m.pointer)) {
    if (e && !cancel) objectMoveTo(e);
    state.objectMove = null;
    const [dx, dy] = m.d;
    const still = m.mode === 'move' ? Math.hypot(dx, dy) < 0.5 : m.mode === 'rotate' ? Math.abs(m.angle) < 0.1 : Math.abs(m.scale - 1) < 1e-3;
    if (cancel || still) {
      renderer.offsetObject(m.rest, m.first, m.count, 0, 0);
      redraw();
      if (cancel) status('move cancelled');
      return true;
    }
    const change = m.mode === 'move' ? { translate: [dx, dy] }
      : m.mode === 'rotate' ? { rotate: m.angle, pivot: m.pivot } : { scale: m.scale, pivot: m.pivot };
    void edit(async () => {
      const f = await postFrame('/api/object/move', {
        session: state.session, version: state.version, level: state.level, object: m.object, ...change,
      });
      applyDelta(f);
      status(f.header.log);
    });
    return true;
  }
  const b = state.objectBox;
  if (b && (!e || e.pointerId === b.pointer)) {
    if (e && !cancel) b.to = canvasPoint(e);
    state.objectBox = null;
    drawObjectBox();
    if (cancel || !state.doc) return true;
    const p = toImage(b.from), q = toImage(b.to);
    const x0 = Math.max(0, Math.floor(Math.min(p[0], q[0]))), y0 = Math.max(0, Math.floor(Math.min(p[1], q[1])));
    const x1 = Math.min(state.doc.width, Math.ceil(Math.max(p[0], q[0]))), y1 = Math.min(state.doc.height, Math.ceil(Math.max(p[1], q[1])));
    if (x1 - x0 < 4 || y1 - y0 < 4) { status('drag a rectangle round what should become an object'); return true; }
    void edit(async () => {
      const f = await postFrame('/api/object/make', {
        session: state.session, version: state.version, level: state.level, rect: [x0, y0, x1 - x0, y1 - y0],
      });
      applyDelta(f);
      status(f.header.log);
    });
    return true;
  }
  return false;
}
async function toggleObject() {
  const o = state.objectSel;
  if (o < 0) { status('select an object with the Object tool (O) first, then press X'); return; }
  const shown = state.objects.some((r) => r.object === o);
  await edit(async () => {
    const f = await postFrame('/api/object/visible', {
      session: state.session, version: state.version, level: state.level, object: o, visible: !shown,
    });
    applyDelta(f);
    status(f.header.log);
  });
}

// ---- input ---------------------------------------------------------------------------------

canvas.addEventListener('pointerdown', (e) => {
  if (!state.doc || !state.session) return;
  const panning = state.tool === 'pan' || e.button === 1 || e.button === 2 || state.space;
  if (panning) {
    const [x, y] = canvasPoint(e);
    state.pan = { x, y, panX: state.transform.panX, panY: state.transform.panY };
    canvas.setPointerCapture(e.pointerId);
    return;
  }
  if (e.button !== 0 || state.drag) return;
  const at = toImage(canvasPoint(e));
  const { width, height } = state.doc;
  if (state.tool !== 'select' && !(at[0] >= 0 && at[1] >= 0 && at[0] <= width && at[1] <= height)) {
    status('outside the image: nothing to pick there');
    return;
  }
  if (state.tool === 'select') void doSelect(at);
  else if (state.tool === 'color') void doColor(at, e.timeStamp || performance.now());
  else if (state.tool === 'points') pointsDown(e);
  else if (state.tool === 'pen') penDown(e);
  else if (state.tool === 'object') objectDown(e);
  else void dragStart(e);
});
canvas.addEventListener('pointermove', (e) => {
  mouseAt = canvasPoint(e);
  if (state.tool === 'color' && !state.pan && !state.drag && e.buttons === 0 && state.doc && state.session) {
    const at = toImage(mouseAt);
    if (at[0] >= 0 && at[1] >= 0 && at[0] <= state.doc.width && at[1] <= state.doc.height) previewRegion(at);
  }
  if (state.pan) {
    const [x, y] = canvasPoint(e);
    state.transform.panX = state.pan.panX + x - state.pan.x;
    state.transform.panY = state.pan.panY + y - state.pan.y;
    state.fitted = false;
    redraw();
    scheduleView();
    return;
  }
  if (state.pen) {
    penMove(e);
    return;
  }
  if (objectMoveTo(e)) return;
  if (state.box && e.pointerId === state.box.pointer) {
    state.box.to = canvasPoint(e);
    state.box.lasso?.push(state.box.to);
    drawBox();
    return;
  }
  dragMove(e);
});
const release = (e: PointerEvent) => {
  if (state.pan) {
    state.pan = null;
    return;
  }
  if (state.box) {
    boxEnd(e);
    return;
  }
  if (state.pen) {
    penEnd(e);
    return;
  }
  if (objectEnd(e)) return;
  dragEnd(e);
};
canvas.addEventListener('pointerup', release);
canvas.addEventListener('pointercancel', (e) => { state.pan = null; boxEnd(e, true); penEnd(e, true); objectEnd(e, true); dragEnd(e, true); });
// A capture lost without a pointerup (the browser took it away): the drag ends there, so that its
// task, which holds the queue, cannot wait for a release that never comes.
canvas.addEventListener('lostpointercapture', (e) => {
  if (state.drag && e.pointerId === state.drag.pointer) dragEnd(e);
  if (state.box && e.pointerId === state.box.pointer) boxEnd(e);
  if (state.pen && e.pointerId === state.pen.pointer) penEnd(e);
  if ((state.objectMove && e.pointerId === state.objectMove.pointer) ||
      (state.objectBox && e.pointerId === state.objectBox.pointer)) objectEnd(e);
});
canvas.addEventListener('contextmenu', (e) => e.preventDefault());
canvas.addEventListener('wheel', (e) => {
  e.preventDefault();
  const [x, y] = canvasPoint(e);
  const t = state.transform;
  const factor = Math.exp(-e.deltaY * (e.deltaMode === 1 ? 0.05 : 0.0015));
  const zoom = Math.min(256, Math.max(0.02, t.zoom * factor));
  t.panX = x - ((x - t.panX) * zoom) / t.zoom;
  t.panY = y - ((y - t.panY) * zoom) / t.zoom;
  t.zoom = zoom;
  state.fitted = false;
  updateZoomLabel();
  redraw();
  scheduleView();
}, { passive: false });

window.addEventListener('keydown', (e) => {
  const target = e.target as HTMLElement;
  if (target && target.tagName === 'INPUT' && ['number', 'text'].includes((target as HTMLInputElement).type)) return;
  const ctrl = e.ctrlKey || e.metaKey;
  const key = e.key.toLowerCase();
  if (ctrl && key === 'z') { e.preventDefault(); void doHistory(e.shiftKey ? 'redo' : 'undo'); return; }
  if (ctrl && key === 'y') { e.preventDefault(); void doHistory('redo'); return; }
  if (ctrl && key === 's') { e.preventDefault(); void doSave(); return; }
  if (ctrl || e.altKey) return;
  if (e.key === 'Tab' && document.activeElement === document.body) { e.preventDefault(); togglePanel(); return; }
  if (e.key === ' ') { state.space = true; canvas.classList.add('pan'); e.preventDefault(); return; }
  const arrows: Record<string, [number, number]> = { arrowleft: [-1, 0], arrowright: [1, 0], arrowup: [0, -1], arrowdown: [0, 1] };
  if (arrows[key] && state.tool === 'points') {
    e.preventDefault();
    const step = e.shiftKey ? 10 : 1;
    nudge(arrows[key][0] * step, arrows[key][1] * step);
    return;
  }
  if (key === 'r') { recolorPoints(); return; }
  if (key === 'escape' && state.tool === 'points' && !state.drag && state.selection.length) { setSelection([]); status('selection cleared'); return; }
  if (key === 'escape' && state.objectSel >= 0 && !state.objectMove && state.doc) {
    state.objectSel = -1;
    showObjects(state.doc);
    status('no object selected: Stylize and Filter act on the level');
    return;
  }
  const tools: Record<string, Tool> = { h: 'pan', v: 'select', d: 'drag', m: 'move', c: 'color', p: 'points', n: 'pen', o: 'object' };
  if (key === 'x' && state.tool === 'object') { void toggleObject(); return; }
  if (tools[key]) { setTool(tools[key]); return; }
  if (key === 'f') { toggleRadio('pick'); return; }
  if (key === 'b') { toggleRadio('mode'); return; }
  if (key === 'y') { void doStylize(); return; }
  if (key === 'i') { eyedropper(); return; }
  if (key === '0') { fit(); return; }
  if (key === '1') { toggleCheck('show-mesh'); return; }
  if (key === '2') { toggleCheck('show-features'); return; }
  if (key === '[') { void setLevel(state.level - 1); return; }
  if (key === ']') { void setLevel(state.level + 1); return; }
  if ((key === 'delete' || key === 'backspace') && state.tool === 'select') { e.preventDefault(); void deletePicked(); return; }
  if (key === 'escape' && state.pen) { penEnd(null, true); return; }
  if (key === 'escape' && (state.objectMove || state.objectBox)) { objectEnd(null, true); return; }
  if (key === 'escape' && state.drag) dragEnd(null, true);
});
window.addEventListener('keyup', (e) => {
  if (e.key === ' ') { state.space = false; canvas.classList.toggle('pan', state.tool === 'pan'); }
});

// The panel folds away in narrow windows (style.css); the toggle and Tab show or hide it.
function togglePanel(open = !document.body.classList.contains('panel-open')) {
  document.body.classList.toggle('panel-open', open);
  $('panel-toggle').setAttribute('aria-expanded', String(open));
}

function toggleRadio(name: string) {
  const inputs = Array.from(document.querySelectorAll<HTMLInputElement>(`input[name=${name}]`));
  const i = inputs.findIndex((x) => x.checked);
  inputs[(i + 1) % inputs.length].checked = true;
}
function toggleCheck(id: string) {
  const box = $<HTMLInputElement>(id);
  box.checked = !box.checked;
  box.dispatchEvent(new Event('change'));
}

function bindOutput(id: string, format: (v: number) => string) {
  const input = $<HTMLInputElement>(id);
  const show = () => { $(`${id}-out`).textContent = format(Number(input.value)); };
  input.addEventListener('input', show);
  show();
}

function wireControls() {
  document.querySelectorAll<HTMLButtonElement>('#tools button').forEach((b) =>
    b.addEventListener('click', () => setTool(b.dataset.tool as Tool)));
  bindOutput('radius', (v) => (v >= RADIUS_NONE ? 'no cap' : `${v} px`));
  bindOutput('tolerance', (v) => `${v}`);
  bindOutput('sigma', (v) => (v === 0 ? 'auto' : `${v} px`));
  bindOutput('region', (v) => (v === 0 ? 'auto' : v >= REGION_WHOLE ? 'whole' : `${v} px`));
  bindOutput('amount', (v) => v.toFixed(2));
  $('level').addEventListener('input', () => void setLevel(num('level')));
  $('show-mesh').addEventListener('change', () => { state.overlays.mesh = $<HTMLInputElement>('show-mesh').checked; redraw(); });
  $('show-features').addEventListener('change', () => { state.overlays.features = $<HTMLInputElement>('show-features').checked; redraw(); });
  $('fit').addEventListener('click', fit);
  $('color').addEventListener('input', () => setColor(hexColor()));
  const colorText = $<HTMLInputElement>('color-text');
  colorText.addEventListener('change', () => {
    const rgb = parseColor(colorText.value);
    if (rgb) {
      setColor(rgb);
    } else {
      colorText.classList.add('bad');
      status(`"${colorText.value}" is not a color: type #rrggbb or r, g, b (0 to 255)`, true);
    }
  });
  $('eyedropper').addEventListener('click', () => status('point at the image and press I to take its color'));
  $('recolor-points').addEventListener('click', () => recolorPoints());
  $('panel-toggle').addEventListener('click', () => togglePanel());
  canvas.addEventListener('pointerdown', () => togglePanel(false));
  $('undo').addEventListener('click', () => void doHistory('undo'));
  $('redo').addEventListener('click', () => void doHistory('redo'));
  $('save').addEventListener('click', () => void doSave());
  $('stylize').addEventListener('click', () => void doStylize());
  $('filter-geometry').addEventListener('change', () => void doFilter());
  $('filter-color').addEventListener('change', () => void doFilter());
  $('filter-reset').addEventListener('click', () => void doFilter(true));
  document.querySelectorAll<HTMLAnchorElement>('.downloads a').forEach((a) =>
    a.addEventListener('click', (e) => { e.preventDefault(); void download(a.dataset.format!); }));
  setTool('drag');
}

// ---- start-up and polling ------------------------------------------------------------------

// This browser tab's id, kept across reloads (sessionStorage is per tab): the server lets a tab
// undo and redo its own edits only, and a reload keeps them.
// This tab's id: the server keeps undo and redo per tab id. sessionStorage keeps it across
// reloads, but a duplicated tab starts with a copy of it. So a tab also holds a Web Lock named
// after its id for as long as it is open: a tab that finds its id's lock taken is a duplicate and
// takes a new id. (Without Web Locks, on plain http away from localhost, duplicates share one.)
let ownTab: Promise<string> | null = null;
function tabId(): Promise<string> {
  ownTab ??= (async () => {
    const fresh = () => Array.from(crypto.getRandomValues(new Uint8Array(12)), (b) => b.toString(16).padStart(2, '0')).join('');
    let id = sessionStorage.getItem('subvec-tab') ?? fresh();
    const locks = navigator.locks;
    while (locks) {
      const held = await new Promise<boolean>((resolve) => {
        void locks.request(`subvec-tab-${id}`, { ifAvailable: true }, (lock) => {
          resolve(lock !== null);
          return lock ? new Promise<void>(() => undefined) : undefined;  // held until the tab closes
        });
      });
      if (held) break;
      id = fresh();
    }
    sessionStorage.setItem('subvec-tab', id);
    return id;
  })();
  return ownTab;
}

async function startSession() {
  state.session = (await postJson('/api/session', { tab: await tabId() })).session;
  await reloadAll();
}

async function waitForDocument() {
  const progress = $('progress');
  for (;;) {
    const s = await getJson('/api/status');
    if (s.state === 'ready') break;
    if (s.state === 'failed') {
      progress.hidden = false;
      $('progress-text').textContent = `Vectorization failed: ${s.error}`;
      throw new Error(s.error);
    }
    progress.hidden = false;
    $('docname').textContent = s.name;
    $('progress-text').textContent =
      `Vectorizing ${s.name}: ${s.stage} ${Math.round(s.fraction * 100)}% (${Math.round(s.seconds)} s)`;
    $('progress-bar').style.width = `${Math.round(s.fraction * 100)}%`;
    await new Promise((r) => setTimeout(r, 300));
  }
  progress.hidden = true;
}

async function poll() {
  try {
    const s = await getJson('/api/status');
    if (s.state === 'ready' && s.version > state.version && state.busy === 0 && !state.drag) {
      await enqueue(async () => {
        if (s.version > state.version) await reloadAll('the document changed in another tab: reloaded');
      });
    }
  } catch {
    // the server may be gone; keep trying quietly
  }
  setTimeout(poll, 1000);
}

// Hooks for the end-to-end tests and the benchmark (web/tests/).
declare global {
  interface Window { subvec: any }
}
window.subvec = {
  state,
  renderer: () => renderer,
  ready: false,
  // RGBA of the canvas at image coordinates (x, y), after a synchronous redraw.
  pixelAt(x: number, y: number) {
    renderer.draw(state.transform, state.overlays);
    const t = state.transform;
    return renderer.readPixel(x * t.zoom + t.panX, y * t.zoom + t.panY);
  },
  // RGBA at many image points, after one synchronous redraw.
  pixelsAt(points: [number, number][]) {
    renderer.draw(state.transform, state.overlays);
    const t = state.transform;
    return points.map(([x, y]) => renderer.readPixel(x * t.zoom + t.panX, y * t.zoom + t.panY));
  },
  // Canvas CSS coordinates (relative to the page) of image point (x, y).
  clientPoint(x: number, y: number) {
    const r = canvas.getBoundingClientRect();
    const dpr = window.devicePixelRatio || 1;
    const t = state.transform;
    return [r.left + (x * t.zoom + t.panX) / dpr, r.top + (y * t.zoom + t.panY) / dpr];
  },
  // The partial redraws' reference: draws what changed since the last frame (a partial frame when it
  // can), then everything, and counts the pixels that differ (0 when partial frames are exact).
  partialFrameErrors() {
    renderer.draw(state.transform, state.overlays);
    const part = renderer.readAll();
    renderer.draw(state.transform, state.overlays, true);
    const whole = renderer.readAll();
    let differ = 0;
    for (let i = 0; i < part.length; i += 4) {
      if (part[i] !== whole[i] || part[i + 1] !== whole[i + 1] || part[i + 2] !== whole[i + 2]) differ++;
    }
    return { differ, frames: { ...renderer.frames } };
  },
  tab: tabId,
  idle() { return state.busy === 0 && !state.drag && downloads === 0; },
  measure(on: boolean) { state.measure = on; state.latencies = []; state.phases = []; state.clicks = []; },
  clicks() { return state.clicks.slice(); },
  latencies() { return state.latencies.slice(); },
  phases() { return state.phases.slice(); },
};

async function main() {
  wireControls();
  try {
    renderer = new Renderer(canvas, quality.antialias);
  } catch (e) {
    status(`cannot draw: ${e instanceof Error ? e.message : e}`, true);
    return;
  }
  new ResizeObserver(resize).observe(canvas);
  resize();
  try {
    await waitForDocument();
    state.session = (await postJson('/api/session', { tab: await tabId() })).session;
    await loadDocument();
    fit();
    await Promise.all([loadView(), loadControl(), loadStrokes()]);
    const doc = state.doc!;
    const l = doc.levels[state.level];
    status(`${doc.name}: ${l.vertices} control vertices, ${l.features} features. Pick a tool in the panel; its description appears below the buttons.`);
    window.subvec.ready = true;
    setTimeout(poll, 1000);
  } catch (e) {
    status(e instanceof Error ? e.message : String(e), true);
  }
}

void main();
