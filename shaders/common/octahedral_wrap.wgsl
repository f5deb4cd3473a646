// The texel of an n × n octahedral map for indices up to one outside it:
// the map's edges fold onto themselves (x = −1 or n mirrored about the
// middle row, y = −1 or n about the middle column). Mirrors
// passes/src/probe/direction_map.rs `wrap_octahedral`.
fn oct_wrap(t: vec2<i32>, n: i32) -> vec2<i32> {
    var x = t.x;
    var y = t.y;
    if x < 0 {
        x = 0;
        y = n - 1 - y;
    } else if x >= n {
        x = n - 1;
        y = n - 1 - y;
    }
    if y < 0 {
        y = 0;
        x = n - 1 - x;
    } else if y >= n {
        y = n - 1;
        x = n - 1 - x;
    }
    return clamp(vec2<i32>(x, y), vec2<i32>(0), vec2<i32>(n - 1));
}
