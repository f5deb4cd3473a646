// Local lights' geometry (passes/src/lighting/local.rs, mirrored function
// for function): the sphere's chord, the disk points its rays aim at, and
// the lobe it shows a point. lighting/local_light.wgsl adds what marches
// the field. A light's emission is (intensity, radius of the disk it
// shines from) as local_intensity measures it. Needs: common/sg.wgsl.

// local.rs ACTIVE_DISTANCE, sgfit MAX_SHARPNESS.
const LOCAL_ACTIVE_DISTANCE: f32 = 2.0;
const LOCAL_MAX_SHARPNESS: f32 = 1.0e4;

fn local_active(sphere: vec4<f32>, origin: vec3<f32>) -> bool {
    return distance(sphere.xyz, origin) > LOCAL_ACTIVE_DISTANCE * sphere.w;
}

// Where origin + t·dir enters and leaves the sphere ahead of the origin;
// (−1, −1) when it does not meet it there.
fn local_chord(sphere: vec4<f32>, origin: vec3<f32>, dir: vec3<f32>) -> vec2<f32> {
    let oc = origin - sphere.xyz;
    let b = dot(oc, dir);
    let c = dot(oc, oc) - sphere.w * sphere.w;
    let disc = b * b - c;
    if disc <= 0.0 {
        return vec2<f32>(-1.0);
    }
    let s = sqrt(disc);
    let t1 = -b + s;
    if t1 <= 0.0 {
        return vec2<f32>(-1.0);
    }
    return vec2<f32>(max(-b - s, 0.0), t1);
}

struct LocalBasis {
    u: vec3<f32>,
    v: vec3<f32>,
}

fn local_basis(w: vec3<f32>) -> LocalBasis {
    let sign = select(-1.0, 1.0, w.z >= 0.0);
    let a = -1.0 / (sign + w.z);
    let b = w.x * w.y * a;
    return LocalBasis(
        vec3<f32>(1.0 + sign * w.x * w.x * a, sign * b, -sign * w.x),
        vec3<f32>(b, sign + w.y * w.y * a, -w.y),
    );
}

// Point k (row-major) of side² on the unit disk (concentric map of cell
// centres).
fn local_disk_point(k: u32, side: u32) -> vec2<f32> {
    let s = max(side, 1u);
    let n = f32(s);
    let a = 2.0 * (f32(k % s) + 0.5) / n - 1.0;
    let b = 2.0 * (f32(k / s) + 0.5) / n - 1.0;
    if a == 0.0 && b == 0.0 {
        return vec2<f32>(0.0);
    }
    let quarter = 0.25 * SG_PI;
    var r = b;
    var phi = 2.0 * quarter - quarter * (a / b);
    if abs(a) > abs(b) {
        r = a;
        phi = quarter * (b / a);
    }
    return vec2<f32>(r * cos(phi), r * sin(phi));
}

// Point k of side² on the disk of `radius` through the light's centre,
// facing `viewer`.
fn local_disk_point_towards(sphere: vec4<f32>, viewer: vec3<f32>, k: u32, side: u32, radius: f32) -> vec3<f32> {
    let f = local_basis(normalize(viewer - sphere.xyz));
    let d = local_disk_point(k, side);
    return sphere.xyz + radius * (d.x * f.u + d.y * f.v);
}

// The lobe a sphere of `radius` at `dist` along `direction`, of
// `intensity`, shows a point (its integral intensity / dist²).
fn local_sphere_lobe(direction: vec3<f32>, dist: f32, radius: f32, intensity: vec3<f32>) -> Sg {
    let d = max(max(dist, radius), 1e-9);
    let s = min(radius / d, 1.0);
    let c = sqrt(max(1.0 - s * s, 0.0));
    let solid = max(2.0 * SG_PI * s * s / (1.0 + c), 1e-12);
    let sharpness = min(2.0 * SG_PI / solid, LOCAL_MAX_SHARPNESS);
    return Sg(direction, sharpness, intensity / (d * d) / sg_sphere_factor(sharpness));
}

