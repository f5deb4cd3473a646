// The list of pixels shadow-upsample flags for shadow-refine: the
// refinement's workgroup size, by which shadow-upsample counts the
// workgroups of its indirect dispatch.
const REFINE_WORKGROUP: u32 = 64u;
