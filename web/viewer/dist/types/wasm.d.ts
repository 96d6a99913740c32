import type { Level, SvecImage } from './image';
import type { PyramidRecord } from './validate';
import type { Refined, Topology } from './subdivide';
export { uniformIndices, type Refined, type Topology } from './subdivide';
/** buildTopology of subdivide.ts. */
export declare function buildTopology(level: Level, width: number, height: number): Topology;
/** refine of subdivide.ts. */
export declare function refine(topo: Topology, faces: Int32Array | null, depth: number): Refined;
/** adaptiveIndices of subdivide.ts. */
export declare function adaptiveIndices(r: Refined, scale: number, colorTolerance: number, positionTolerance: number): Uint32Array;
/** zstd's content checksum of b: the low 32 bits of XXH64, seed 0 (wasm/checksum.c). */
export declare function checksum(b: Uint8Array): number;
/** A compact level's counts, precision and bytes (one stream, or six sections), as decode.ts read them. */
export interface CompactInput {
    version: number;
    sections: Uint8Array[];
    ops: number;
    nv: number;
    ncolors: number;
    ntriangles: number;
    ncreases: number;
    nfeatures: number;
    pb: number;
    cb: number;
    width: number;
    height: number;
    /** the level's number, for the messages */
    level: number;
}
/** The edges of a level the decoder built, sorted by (a, b) with a < b, and the triangle across
 * each (-1 on the border): what check_level needs of them. */
export interface Edges {
    a: Int32Array;
    b: Int32Array;
    g: Int32Array;
}
/** A compact level and its edges, or a SvecError naming the problem. */
export declare function decodeCompact(input: CompactInput): [Level, Edges];
/** Throws a SvecError naming the first validity rule (docs/format.md) that level l breaks.
 * `built`: the edges of a level the decoder built, whose colors, indices and topology are valid
 * by construction. */
export declare function checkLevel(level: Level, width: number, height: number, l: number, built?: Edges): void;
/** A .svec.json file's image (before validate()) and its pyramid records, or a SvecError. */
export declare function readJson(b: Uint8Array): [SvecImage, PyramidRecord[]];
