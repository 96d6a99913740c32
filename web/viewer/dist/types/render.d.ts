import { type SvecImage } from './image';
/** A region of the image, in image pixels. */
export interface ViewWindow {
    x0: number;
    y0: number;
    x1: number;
    y1: number;
}
export interface RenderStats {
    /** subdivision depth of the last frame */
    depth: number;
    /** triangles drawn */
    triangles: number;
    /** milliseconds spent refining for the last frame (0 when it reused the refinement) */
    refineMs: number;
    /** milliseconds spent issuing the draw calls */
    drawMs: number;
}
export declare const DEFAULT_MAX_EDGE_PIXELS = 5;
export declare function chooseDepth(meanEdgePixels: number, maxEdgePixels: number, zoom: number, faces: number): number;
/** Whether w is a window: finite, x0 < x1 and y0 < y1. */
export declare const validWindow: (w: ViewWindow) => boolean;
export declare class SubvecRenderer {
    #private;
    readonly canvas: HTMLCanvasElement | OffscreenCanvas;
    readonly stats: RenderStats;
    /** The depth rule's refined edge length at 1x, in output pixels: 2.5 draws what `subvec render` draws. */
    maxEdgePixels: number;
    /**
     * How far (in color levels) a control face's triangles may be from the next level's before it
     * is refined further, up to the depth rule's depth; 0 refines every face to that depth.
     */
    colorTolerance: number;
    /** The same for tear and border curves, in output pixels. */
    positionTolerance: number;
    constructor(canvas: HTMLCanvasElement | OffscreenCanvas);
    /** Shows `image` (already validated by decode/load) at `level`. */
    setImage(image: SvecImage, level?: number): void;
    setLevel(level: number): void;
    /** The region of the image mapped onto the whole canvas; null: the whole image. */
    setView(window: ViewWindow | null): void;
    /** Draws at canvas.width x canvas.height device pixels; outside the image stays transparent. */
    render(): void;
    /** Frees the GPU resources; the renderer cannot draw afterwards. */
    dispose(): void;
}
