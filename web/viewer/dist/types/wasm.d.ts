import type { Level, SvecImage } from './image';
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
/** A .svec.json file's image, validated, or a SvecError. */
export declare const readJson: (b: Uint8Array) => SvecImage;
/** A .svec payload's image, validated, or a SvecError. `flags`: the header's (1: the payload
 * holds objects, 2: and their strokes). */
export declare const readPayload: (b: Uint8Array, version: number, flags: number) => SvecImage;
/** A .svec file's header and its zstd frame's header and blocks checked (wasm/json.c): the
 * payload's size, the frame's end, what a cut raw block gives, the frame descriptor, the version, the flags. */
export declare const container: (b: Uint8Array) => Float64Array<ArrayBuffer>;
