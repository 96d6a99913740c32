import { type SvecImage } from './image';
import { SubvecRenderer, type ViewWindow } from './render';
declare const Base: typeof HTMLElement;
export declare class SubvecImageElement extends Base {
    static get observedAttributes(): string[];
    private canvas;
    private sizeStyle;
    private renderer;
    private current;
    private shownLevel;
    private ready;
    private window;
    private errorText;
    private generation;
    private abort;
    private frame;
    private resize;
    private drag;
    private readonly wheel;
    constructor();
    connectedCallback(): void;
    disconnectedCallback(): void;
    private makeCanvas;
    private makeRenderer;
    private forgetRenderer;
    attributeChangedCallback(name: string, old: string | null, value: string | null): void;
    get src(): string;
    set src(value: string);
    /** The level of detail drawn: 0 (the finest, default) up to the file's level count - 1. */
    get level(): number;
    set level(value: number);
    /** Wheel zooms about the pointer, a drag pans, a double click shows the whole image again. */
    get interactive(): boolean;
    set interactive(on: boolean);
    /** The message of the last problem (loading, decoding, drawing), null when there is none. */
    get error(): string | null;
    /** The decoded file, null until it is loaded. */
    get image(): SvecImage | null;
    get naturalWidth(): number;
    get naturalHeight(): number;
    /** What the last frame cost (the renderer's stats), null before the first one. */
    get stats(): SubvecRenderer['stats'] | null;
    /**
     * The image region shown (image pixels), fitted into the element and centred; null: the whole
     * image. Setting it draws again at the next frame.
     */
    get view(): ViewWindow | null;
    set view(w: ViewWindow | null);
    setView(w: ViewWindow | null): void;
    private startLoad;
    private setNaturalSize;
    private prepare;
    private schedule;
    private draw;
    private shownWindow;
    private changeView;
    private imagePoint;
    private onWheel;
    private onPointerDown;
    private onPointerMove;
    private onPointerUp;
    private fail;
    private emit;
}
export {};
