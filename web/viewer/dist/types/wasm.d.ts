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
/** The edges of a level the decoder built, sorted by (a, b) with a < b, and the triangle across
 * each (-1 on the border): what check_level needs of them. */
export interface Edges {
    a: Int32Array;
    b: Int32Array;
    g: Int32Array;
}
/** Throws a SvecError naming the first validity rule (docs/format.md) that level l breaks.
 * `built`: the edges of a level the decoder built, whose colors, indices and topology are valid
 * by construction. */
export declare const checkLevel: (level: Level, width: number, height: number, l: number, built?: Edges) => void;
/** The same for object `index`'s mesh (docs/format.md, "Objects"): it need not tile the image. */
export declare const checkObject: (mesh: Level, index: number) => void;
/** A .svec.json file's image (before validate()), its pyramid records (and its objects'), or a SvecError. */
export declare const readJson: (b: Uint8Array) => [SvecImage, PyramidRecord[], Edges[], PyramidRecord[]];
/** A .svec payload's image (before validate()), its pyramid records, the compact levels' edges
 * and its objects' records, or a SvecError. `flags`: the header's (1: the payload holds objects). */
export declare const readPayload: (b: Uint8Array, version: number, flags: number) => [SvecImage, PyramidRecord[], Edges[], PyramidRecord[]];
/** A .svec file's header and its zstd frame's header and blocks checked (wasm/json.c): the
 * payload's size, the frame's end, what a cut raw block gives, the frame descriptor, the version, the flags. */
export declare const container: (b: Uint8Array) => Float64Array<ArrayBuffer>;
