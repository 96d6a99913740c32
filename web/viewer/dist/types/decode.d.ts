import { SvecImage } from './image';
/** Decodes and validates a .svec (binary versions 1, 2, 3) or .svec.json file from its bytes.
 * Throws SvecError with a one-line message (prefixed with `name` when given). */
export declare function decode(bytes: Uint8Array | ArrayBuffer, name?: string): SvecImage;
/** fetch()es a URL (or reads a Blob/File, or takes an ArrayBuffer/Uint8Array) and decodes it.
 * Rejects with SvecError (HTTP status, network failure, or decode error), never anything else. */
export declare function load(source: string | URL | Blob | ArrayBuffer | Uint8Array, init?: RequestInit): Promise<SvecImage>;
