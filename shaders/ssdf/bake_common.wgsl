// What the SSDF bake's kernels that cast rays share (ssdf_outer.wgsl
// judges each silhouette piece, ssdf_bake.wgsl measures every direction
// against the outline): the push block, the points and the BVH.
#include "ssdf/bake_push.wgsl"
@group(0) @binding(2) var<storage, read> bvh_nodes: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> bvh_triangles: array<vec4<f32>>;

#include "geometry/mesh_bvh.wgsl"
