import { type SvecImage } from './image';
import { SubvecRenderer, type ViewWindow } from './render';
declare const Base: typeof HTMLElement;
export declare class SubvecImageElement extends Base {
    #private;
    static get observedAttributes(): string[];
    constructor();
    connectedCallback(): void;
    disconnectedCallback(): void;
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
}
export {};
