// Counts the iterations its loops run, to pin down how the device limits
// them (tests/loop_limit.rs): mode 0 one loop of n, mode 1 two loops of n
// after another, mode 2 a loop of n inside a loop of n, mode 3 a loop of
// 8 inside a loop of n.

struct LoopCountPush {
    n: u32,
    mode: u32,
    _pad0: u32,
    _pad1: u32,
}

var<immediate> pc: LoopCountPush;

@group(0) @binding(0) var<storage, read_write> counted: array<u32>;

@compute @workgroup_size(1, 1, 1)
fn main() {
    var c = 0u;
    if pc.mode == 0u {
        for (var i = 0u; i < pc.n; i++) {
            c += 1u;
        }
    } else if pc.mode == 1u {
        for (var i = 0u; i < pc.n; i++) {
            c += 1u;
        }
        for (var i = 0u; i < pc.n; i++) {
            c += 1u;
        }
    } else if pc.mode == 2u {
        for (var i = 0u; i < pc.n; i++) {
            for (var j = 0u; j < pc.n; j++) {
                c += 1u;
            }
        }
    } else {
        for (var i = 0u; i < pc.n; i++) {
            for (var j = 0u; j < 8u; j++) {
                c += 1u;
            }
        }
    }
    counted[0] = c;
}
