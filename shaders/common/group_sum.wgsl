// The sum over a workgroup of 64 invocations of each one's `part`, by a
// tree through workgroup memory. Every invocation of the group calls it
// (it holds barriers), each gets the total.

var<workgroup> group_sums: array<vec4<f32>, 64>;

fn group_sum(lid: u32, part: vec4<f32>) -> vec4<f32> {
    group_sums[lid] = part;
    workgroupBarrier();
    for (var stride = 32u; stride > 0u; stride = stride / 2u) {
        if lid < stride {
            group_sums[lid] += group_sums[lid + stride];
        }
        workgroupBarrier();
    }
    let total = group_sums[0];
    workgroupBarrier();
    return total;
}
