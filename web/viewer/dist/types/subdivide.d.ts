import type { Level } from './image';
export declare const SMOOTH = 0;
export declare const SHARP = 1;
export declare const TEAR = 2;
export declare const BORDER = 3;
/** A level's control topology, built once: edges, tags, vertex stars and ring boxes. */
export interface Topology {
    level: Level;
    numEdges: number;
    triEdges: Int32Array;
    edgeVerts: Int32Array;
    edgeTags: Uint8Array;
    corner: Uint8Array;
    /** faces around each vertex (CSR) */
    vertexFaceOffsets: Int32Array;
    vertexFaces: Int32Array;
    /** per face the bounding box (x0, y0, x1, y1) of the control points its limit patch depends on */
    ringBoxes: Float64Array;
}
/** The topology of a level of a `width` x `height` image; NaN for both: an object's mesh, which has
 * no image corners (its boundary vertices are creases, as in MeshTopology::build with kNoFrame). */
export declare function buildTopology(level: Level, width: number, height: number): Topology;
/** The limit surface over the selected faces: one vertex per color value. */
export interface Refined {
    depth: number;
    /** x, y, r, g, b per color value of the last level (image pixels; 0-255 colors, unclamped) */
    vertices: Float32Array;
    /** the selected faces are the sub-mesh's faces 0 .. selected - 1 */
    selected: number;
    /**
     * Every level's triangles as color values (3 per face; a value keeps its number in later
     * levels, so they index `vertices` too; the children of face t are faces 4t .. 4t + 3 of the
     * next level, 4t + 3 the middle one) and the sub-mesh edge each side lies on (-1: inside a
     * control face).
     */
    levels: Array<{
        values: Int32Array;
        sides: Int32Array;
    }>;
    /** per sub-mesh edge: 1 when it is a tear or on the border */
    sharpEdges: Uint8Array;
    /** per sub-mesh edge its two sub-mesh faces (-1: none) */
    edgeFaces: Int32Array;
}
/**
 * Refines `faces` (control face indices; all faces when null) `depth` times and pushes the result
 * to the limit. The one-ring of the faces is refined with them so that their children are exact.
 */
export declare function refine(topo: Topology, faces: Int32Array | null, depth: number): Refined;
/** The last level's triangles over the selected faces: the uniform refinement. */
export declare function uniformIndices(r: Refined): Uint32Array;
/**
 * Triangles over the selected faces, each control face only as deep as it needs: the shallowest
 * level whose triangles are within `colorTolerance` (levels) of the next level's points, measured
 * where those points are drawn, and whose tear and border sides are within `positionTolerance`
 * output pixels of them (`scale` output pixels per image pixel). Faces that share an edge differ by
 * at most one level, and the coarser one takes the finer one's points on that edge (its triangles
 * there split in two, three or four): no cracks, no T-junctions, every point a limit point.
 */
export declare function adaptiveIndices(r: Refined, scale: number, colorTolerance: number, positionTolerance: number): Uint32Array;
