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
/** Control characters as \xNN, for one-line messages. */
export declare const escape: (s: string) => string;
/** The corner after h in its triangle, and the one before. */
export declare const next3: (h: number) => number;
export declare const prev3: (h: number) => number;
/** A stable counting sort of `items` (default 0..key.length-1) by key[i], 0 <= key[i] < n: the
 * items in order, and where each key's run starts (run k is start[k] to start[k + 1]). */
export declare function sortBy(key: ArrayLike<number>, n: number, items?: Int32Array): [Int32Array, Int32Array];
/** The edges of a level, sorted by (a, b) with a < b: their triangles (g = -1 on the border) and
 * tags (0 smooth, 1 crease, 2 tear, 3 border); and the twin of each half-edge (corner h stands
 * for the half-edge from t[h] to t[next3(h)]), -1 on the border. */
export interface Topology {
    a: Int32Array;
    b: Int32Array;
    f: Int32Array;
    g: Int32Array;
    tag: Uint8Array;
    twin: Int32Array;
}
/** The edges of triangles t over nv vertices (MeshTopology::build without the creases and
 * features), or the message of the first problem. */
export declare function edges(t: Int32Array, nv: number): Topology | string;
/** MeshTopology::build without the vertex tags: the edges (given, or found), creases and
 * features marked; `prefix` starts its messages. */
export declare function topology(m: Level, nv: number, prefix?: string, found?: string | Topology): Topology;
/** face_varying_indices: one color index per wedge (corners of a vertex joined across edges
 * that are not tears), numbered in order of first use; and their count. */
export declare function wedges(m: Level, { a, b, f, g, tag }: Topology): [Int32Array, number];
/** Throws a SvecError naming the first rule of docs/format.md ("Validity rules") that the image
 * breaks. `records` are the pyramid records by level, where the file has them; `topologies` those
 * of levels the decoder has already built. */
export declare function validate(image: SvecImage, records?: Array<PyramidRecord | undefined>, topologies?: Topology[]): void;
