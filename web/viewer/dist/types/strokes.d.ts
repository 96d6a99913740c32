import type { Stroke } from './image';
/** Maps image pixels to output pixels. */
export interface ViewTransform {
    x0: number;
    y0: number;
    sx: number;
    sy: number;
    width: number;
    height: number;
}
/** 6 floats per chord (x0, y0, x1, y1, r0, r1) in output pixels; empty when it misses the view. */
export declare function strokeChords(stroke: Stroke, view: ViewTransform): Float32Array;
