// subvec-viewer: .svec / .svec.json files in the browser (WebGL2). Importing it registers
// <subvec-image>; pages that want control use load() and SubvecRenderer (docs/viewer.md).
import { SubvecImageElement } from './element';

export { decode, load } from './decode';
export { SvecError } from './image';
export type { Feature, Level, Stroke, SvecImage, SvecObject } from './image';
export { SubvecRenderer } from './render';
export type { ViewWindow } from './render';
export { SubvecImageElement };

// Guarded so that the module also imports where there is no DOM (node, workers), and so that a
// second copy of the module on the page does not throw on the name taken by the first.
if (typeof customElements !== 'undefined' && !customElements.get('subvec-image')) {
  customElements.define('subvec-image', SubvecImageElement);
}

declare global {
  interface HTMLElementTagNameMap {
    'subvec-image': SubvecImageElement;
  }
}
