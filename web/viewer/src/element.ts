// <subvec-image src="photo.svec" level="0" interactive>: a .svec file on a page, laid out like an
// <img>. The image is fitted (contain) and centred; `view` zooms and pans. Problems become an
// `error` event and the `error` property, never an exception reaching the page.
import { load } from './decode';
import { SvecError, type SvecImage } from './image';
import { SubvecRenderer, validWindow, type ViewWindow } from './render';

// Like an <img>: inline-block, W x H CSS pixels by default, one side set by CSS gives the other
// through the aspect ratio. Size containment keeps the canvas from feeding back into the size;
// the page's own CSS overrides all of this, as outer styles beat :host.
const STYLE = `:host{display:inline-block;position:relative;overflow:hidden;contain:size}
canvas{position:absolute;left:0;top:0;width:100%;height:100%;display:block}
:host([interactive]) canvas{cursor:grab;touch-action:none}`;

const MAX_ZOOM = 4096;  // the view at most 4096x the image's pixels; at least 1/8 of them

// HTMLElement is missing in node: the module must still import there (index.ts registers nothing).
const Base = (typeof HTMLElement === 'undefined' ? class {} : HTMLElement) as typeof HTMLElement;

function message(e: unknown): string {
  const text = e instanceof Error ? e.message : String(e);
  return text.split('\n')[0];
}

export class SubvecImageElement extends Base {
  static get observedAttributes(): string[] {
    return ['src', 'level', 'interactive'];
  }

  #canvas: HTMLCanvasElement;
  #sizeStyle: HTMLStyleElement;
  #renderer: SubvecRenderer | null = null;
  #current: SvecImage | null = null;
  #shownLevel = -1;      // the level last handed to the renderer, -1: none
  #ready = false;        // the renderer holds this.#current at shownLevel
  #window: ViewWindow | null = null;
  #errorText: string | null = null;
  #generation = 0;       // a newer src makes older loads' results stale
  #abort: AbortController | null = null;
  #frame = 0;            // the pending requestAnimationFrame, 0: none
  #resize: ResizeObserver | null = null;
  #drag: { id: number; x: number; y: number; view: ViewWindow } | null = null;
  readonly #wheel = (e: WheelEvent) => this.#onWheel(e);

  constructor() {
    super();
    const root = this.attachShadow({ mode: 'open' });
    const style = document.createElement('style');
    style.textContent = STYLE;
    this.#sizeStyle = document.createElement('style');
    this.#canvas = this.#makeCanvas();
    root.append(style, this.#sizeStyle, this.#canvas);
    this.addEventListener('pointerdown', (e) => this.#onPointerDown(e));
    this.addEventListener('pointermove', (e) => this.#onPointerMove(e));
    this.addEventListener('pointerup', (e) => this.#onPointerUp(e));
    this.addEventListener('pointercancel', (e) => this.#onPointerUp(e));
    this.addEventListener('dblclick', () => {
      if (this.interactive) this.#changeView(null);
    });
  }

  connectedCallback(): void {
    if (typeof ResizeObserver !== 'undefined' && !this.#resize) {
      this.#resize = new ResizeObserver(() => this.#schedule());
      // The device-pixel box also changes with the device pixel ratio (browser zoom, screens).
      try {
        this.#resize.observe(this.#canvas, { box: 'device-pixel-content-box' });
      } catch {
        this.#resize.observe(this.#canvas);  // browsers without that box
      }
    }
    this.#makeRenderer();
    this.#schedule();
  }

  disconnectedCallback(): void {
    // Browsers keep few WebGL contexts alive: give this one back; a reconnect draws on a new canvas.
    this.#resize?.disconnect();
    this.#resize = null;
    if (this.#frame) cancelAnimationFrame(this.#frame);
    this.#frame = 0;
    this.#renderer?.dispose();
    this.#forgetRenderer();
    const fresh = this.#makeCanvas();
    this.#canvas.replaceWith(fresh);
    this.#canvas = fresh;
  }

  // A lost context (a GPU reset, too many contexts) comes back when the page asks for that; the
  // renderer's GL objects died with it, so a new renderer draws on the restored one.
  #makeCanvas(): HTMLCanvasElement {
    const canvas = document.createElement('canvas');
    canvas.addEventListener('webglcontextlost', (e) => e.preventDefault());
    canvas.addEventListener('webglcontextrestored', () => {
      this.#forgetRenderer();
      this.#schedule();
    });
    return canvas;
  }

  // The renderer (its context and shaders) gets ready while the file is in flight; a failure
  // here is reported by prepare() once the file is in.
  #makeRenderer(): void {
    if (!this.isConnected || this.#renderer || !this.#abort) return;
    try {
      this.#renderer = new SubvecRenderer(this.#canvas);
    } catch {
      // prepare() tries again and reports it
    }
  }

  #forgetRenderer(): void {
    this.#renderer = null;
    this.#ready = false;
    this.#shownLevel = -1;
  }

  attributeChangedCallback(name: string, old: string | null, value: string | null): void {
    if (old === value) return;
    if (name === 'src') this.#startLoad(value);
    else if (name === 'level') this.#schedule();
    // Only an interactive element takes the wheel: a blocking wheel listener slows scrolling.
    else if (value === null) this.removeEventListener('wheel', this.#wheel);
    else this.addEventListener('wheel', this.#wheel, { passive: false });
  }

  get src(): string {
    return this.getAttribute('src') ?? '';
  }
  set src(value: string) {
    this.setAttribute('src', value);
  }

  /** The level of detail drawn: 0 (the finest, default) up to the file's level count - 1. */
  get level(): number {
    const n = Number(this.getAttribute('level') ?? 0);
    return Number.isInteger(n) && n >= 0 ? n : 0;
  }
  set level(value: number) {
    this.setAttribute('level', String(value));
  }

  /** Wheel zooms about the pointer, a drag pans, a double click shows the whole image again. */
  get interactive(): boolean {
    return this.hasAttribute('interactive');
  }
  set interactive(on: boolean) {
    this.toggleAttribute('interactive', on);
  }

  /** The message of the last problem (loading, decoding, drawing), null when there is none. */
  get error(): string | null {
    return this.#errorText;
  }

  /** The decoded file, null until it is loaded. */
  get image(): SvecImage | null {
    return this.#current;
  }

  get naturalWidth(): number {
    return this.#current?.width ?? 0;
  }
  get naturalHeight(): number {
    return this.#current?.height ?? 0;
  }

  /** What the last frame cost (the renderer's stats), null before the first one. */
  get stats(): SubvecRenderer['stats'] | null {
    return this.#renderer && this.#shownLevel >= 0 ? this.#renderer.stats : null;
  }

  /**
   * The image region shown (image pixels), fitted into the element and centred; null: the whole
   * image. Setting it draws again at the next frame.
   */
  get view(): ViewWindow | null {
    return this.#window ? { ...this.#window } : null;
  }
  set view(w: ViewWindow | null) {
    this.setView(w);
  }

  setView(w: ViewWindow | null): void {
    if (w !== null && !(w && typeof w === 'object' && validWindow(w))) {
      this.#fail(new SvecError('view window must have finite x0 < x1 and y0 < y1, or be null'));
      return;
    }
    this.#window = w ? { x0: w.x0, y0: w.y0, x1: w.x1, y1: w.y1 } : null;
    this.#schedule();
  }

  #startLoad(src: string | null): void {
    const generation = ++this.#generation;
    this.#abort?.abort();
    this.#abort = null;
    this.#current = null;
    this.#ready = false;
    this.#shownLevel = -1;
    this.#errorText = null;
    this.#setNaturalSize(null);
    this.#schedule();  // hides the old picture
    if (!src) return;
    this.#abort = new AbortController();
    this.#makeRenderer();
    // fetch() resolves src against the page, and messages name it as the page wrote it.
    load(src, { signal: this.#abort.signal })
      .then((image) => {
        if (generation !== this.#generation) return;
        this.#current = image;
        this.#setNaturalSize(image);
        // The level is checked now, so that a bad one is this load's error rather than a load.
        if (this.#prepare()) {
          this.#emit('load', { width: image.width, height: image.height, levels: image.levels.length });
        }
      })
      .catch((e) => {
        if (generation === this.#generation) this.#fail(e);
      });
  }

  // The fallback width is for browsers without contain-intrinsic-size (Safari before 17), where
  // a CSS height alone then letterboxes the image instead of setting the width.
  #setNaturalSize(image: SvecImage | null): void {
    const w = image?.width, h = image?.height;
    this.#sizeStyle.textContent = image
      ? `:host{aspect-ratio:${w}/${h};contain-intrinsic-size:${w}px ${h}px}` +
        `@supports not (contain-intrinsic-size:1px){:host{width:${w}px}}`
      : '';
  }

  // Gives the renderer (made at first use) the image at the wanted level. Tried once per level:
  // false, with one error event, when that fails.
  #prepare(): boolean {
    if (!this.#current) return false;
    if (this.#shownLevel === this.level) return this.#ready;
    this.#shownLevel = this.level;
    this.#ready = false;
    try {
      this.#renderer ??= new SubvecRenderer(this.#canvas);
      this.#renderer.setImage(this.#current, this.level);
      this.#ready = true;
      this.#errorText = null;
    } catch (e) {
      this.#fail(e);
    }
    this.#schedule();
    return this.#ready;
  }

  // Re-renders are coalesced: any number of changes within a frame draw once.
  #schedule(): void {
    if (this.#frame || typeof requestAnimationFrame === 'undefined') return;
    this.#frame = requestAnimationFrame(() => {
      this.#frame = 0;
      this.#draw();
    });
  }

  #draw(): void {
    if (!this.isConnected) return;
    const shown = this.#prepare();
    // Nothing is shown while loading or after a failure, as an <img> shows no stale picture.
    this.#canvas.style.visibility = shown ? '' : 'hidden';
    if (!shown || !this.#renderer) return;
    const ratio = window.devicePixelRatio || 1;
    // Read now, not from the ResizeObserver: its sizes come after this frame's layout.
    const width = Math.round(this.#canvas.clientWidth * ratio);
    const height = Math.round(this.#canvas.clientHeight * ratio);
    if (width < 1 || height < 1) return;  // not laid out: the ResizeObserver calls again
    if (this.#canvas.width !== width) this.#canvas.width = width;
    if (this.#canvas.height !== height) this.#canvas.height = height;
    try {
      this.#renderer.setView(this.#shownWindow());
      this.#renderer.render();
      this.#emit('render', { ...this.#renderer.stats });
    } catch (e) {
      this.#fail(e);
    }
  }

  // The view (or the whole image) grown to the canvas's aspect about its centre: contain, centred.
  #shownWindow(): ViewWindow {
    const image = this.#current!;
    const w = this.#window ?? { x0: 0, y0: 0, x1: image.width, y1: image.height };
    const aspect = this.#canvas.width / this.#canvas.height;
    const cx = (w.x0 + w.x1) / 2, cy = (w.y0 + w.y1) / 2;
    let hw = (w.x1 - w.x0) / 2, hh = (w.y1 - w.y0) / 2;
    if (hw / hh < aspect) hw = hh * aspect;
    else hh = hw / aspect;
    return { x0: cx - hw, y0: cy - hh, x1: cx + hw, y1: cy + hh };
  }

  // A view change by the user: kept as the window shown, so that later steps do not drift.
  #changeView(w: ViewWindow | null): void {
    this.#window = w;
    this.#schedule();
    this.#emit('viewchange', this.view);
  }

  // The image point under a client position, in the window shown now.
  #imagePoint(e: MouseEvent, w: ViewWindow): [number, number] {
    const r = this.#canvas.getBoundingClientRect();
    const u = r.width > 0 ? (e.clientX - r.left) / r.width : 0.5;
    const v = r.height > 0 ? (e.clientY - r.top) / r.height : 0.5;
    return [w.x0 + u * (w.x1 - w.x0), w.y0 + v * (w.y1 - w.y0)];
  }

  #onWheel(e: WheelEvent): void {
    if (!this.interactive || !this.#ready || !this.#canvas.width) return;
    e.preventDefault();
    const w = this.#shownWindow();
    const [px, py] = this.#imagePoint(e, w);
    const pixels = e.deltaMode === 1 ? e.deltaY * 16 : e.deltaMode === 2 ? e.deltaY * 400 : e.deltaY;
    const ww = w.x1 - w.x0, iw = this.#current!.width;
    // > 1 zooms out; kept between MAX_ZOOM x and an eighth of the image's size
    const f = Math.min(Math.max(Math.exp(pixels * 0.002), iw / MAX_ZOOM / ww), (8 * iw) / ww);
    this.#changeView({ x0: px + (w.x0 - px) * f, y0: py + (w.y0 - py) * f,
      x1: px + (w.x1 - px) * f, y1: py + (w.y1 - py) * f });
  }

  #onPointerDown(e: PointerEvent): void {
    if (!this.interactive || !this.#ready || e.button !== 0 || !this.#canvas.width) return;
    this.#drag = { id: e.pointerId, x: e.clientX, y: e.clientY, view: this.#shownWindow() };
    this.setPointerCapture(e.pointerId);
    this.#canvas.style.cursor = 'grabbing';
  }

  #onPointerMove(e: PointerEvent): void {
    const d = this.#drag;
    if (!d || e.pointerId !== d.id) return;
    const scale = (d.view.x1 - d.view.x0) / Math.max(1, this.#canvas.clientWidth);
    const dx = (e.clientX - d.x) * scale, dy = (e.clientY - d.y) * scale;
    this.#changeView({ x0: d.view.x0 - dx, y0: d.view.y0 - dy, x1: d.view.x1 - dx, y1: d.view.y1 - dy });
  }

  #onPointerUp(e: PointerEvent): void {
    if (!this.#drag || e.pointerId !== this.#drag.id) return;
    this.#drag = null;
    this.#canvas.style.cursor = '';
  }

  #fail(e: unknown): void {
    this.#errorText = message(e);
    this.#emit('error', { message: this.#errorText });
  }

  // A listener's exception is reported by the browser and does not come back out of here.
  #emit(type: string, detail: unknown): void {
    this.dispatchEvent(new CustomEvent(type, { detail }));
  }
}
