import { Level, SvecImage } from './image';
export declare const MAX_ELEMENTS: number;
export declare const MAX_LEVELS = 64;
export declare const MAX_DIMENSION = 65536;
/** A level's pyramid record (docs/format.md, "Levels and the pyramid"): the parent of each vertex
 * in the level before, and the collapses [removed, kept] that made the level, flattened. */
export interface PyramidRecord {
    parents: ArrayLike<number>;
    collapses: ArrayLike<number>;
}
export declare function fail(message: string): never;
/** v as printf's "%g" writes it (6 significant digits), as the C++ messages print numbers. */
export declare function num(v: number): string;
/** Indices 0..n-1 of the pairs (a[i], b[i]) ordered by (a, b, i), and where each value of a
 * (0 <= a < nv) starts: a counting sort on a, then each run by b, stably (MeshTopology::build). */
export declare function sortPairs(a: Int32Array, b: Int32Array, nv: number): [Int32Array, Int32Array];
/** The edges of a level, sorted by (a, b) with a < b: their triangles (g = -1 on the border) and
 * tags (0 smooth, 1 crease, 2 tear, 3 border). */
export interface Topology {
    a: Int32Array;
    b: Int32Array;
    f: Int32Array;
    g: Int32Array;
    tag: Uint8Array;
}
/** MeshTopology::build without the vertex tags. Messages have no "level L: " prefix. */
export declare function topology(m: Level, nv: number): Topology;
/** face_varying_indices: one color index per wedge (corners of a vertex joined across edges
 * that are not tears), numbered in order of first use; and their count. */
export declare function wedges(m: Level, topo: Topology): [Int32Array, number];
/** Throws a SvecError naming the first rule of docs/format.md ("Validity rules") that the image
 * breaks. `records` are the pyramid records by level, where the file has them. */
export declare function validate(image: SvecImage, records?: Array<PyramidRecord | undefined>): void;
