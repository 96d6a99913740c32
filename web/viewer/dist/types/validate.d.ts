import { SvecImage } from './image';
import { type Edges } from './wasm';
export declare const MAX_ELEMENTS: number;
export declare const MAX_LEVELS = 64;
export declare const MAX_DIMENSION = 65536;
export declare const MAX_OBJECTS = 4096;
/** A level's pyramid record (docs/format.md, "Levels and the pyramid"): the parent of each vertex
 * in the level before, and the collapses [removed, kept] that made the level, flattened. */
export interface PyramidRecord {
    parents: ArrayLike<number>;
    collapses: ArrayLike<number>;
}
export declare function fail(message: string): never;
/** Control characters as \xNN, for one-line messages. */
export declare const escape: (s: string) => string;
/** Throws a SvecError naming the first rule of docs/format.md ("Validity rules") that the image
 * breaks. `records` are the pyramid records by level, where the file has them; `topologies` those
 * of levels the decoder has already built; `objectRecords` what the objects' meshes name of a
 * pyramid record (nothing is allowed). */
export declare function validate(image: SvecImage, records?: Array<PyramidRecord | undefined>, topologies?: Edges[], objectRecords?: Array<PyramidRecord | undefined>): void;
