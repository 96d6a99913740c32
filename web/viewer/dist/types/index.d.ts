import { SubvecImageElement } from './element';
export { decode, load } from './decode';
export { SvecError } from './image';
export type { Feature, Level, Stroke, SvecImage, SvecObject } from './image';
export { SubvecRenderer } from './render';
export type { ViewWindow } from './render';
export { SubvecImageElement };
declare global {
    interface HTMLElementTagNameMap {
        'subvec-image': SubvecImageElement;
    }
}
