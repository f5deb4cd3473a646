// Appending a pixel to the list shadow-refine runs over: its index (y·w +
// x of the image it indexes) into refine_list, counted in refine_count,
// and the list's workgroups of REFINE_WORKGROUP in refine_args (the
// refinement's indirect dispatch). The including shader declares
// refine_count (atomic<u32>), refine_list (array<u32>) and refine_args
// (array<atomic<u32>, 3>), all read_write.
#include "shadow/refine_list.wgsl"

fn refine_append(index: u32) {
    let i = atomicAdd(&refine_count, 1u);
    refine_list[i] = index;
    if i % REFINE_WORKGROUP == 0u {
        atomicAdd(&refine_args[0], 1u);
    }
}
