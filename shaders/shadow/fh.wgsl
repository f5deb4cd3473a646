// The visible fraction q(θ, λ) = f_h(θ, λ) / f_h(π/2, λ) of an SG behind a
// great circle at signed angle θ from its axis, read bilinearly from the
// table of passes/src/shadow/fh.rs (FhTable::fraction is the mirror):
// rows log-spaced in λ over [FH_SHARPNESS_MIN, FH_SHARPNESS_MAX], columns
// at tanh(sθ)/tanh(sπ/2), s = √λ/2; θ saturates at ±π/2.
// Needs: storage buffer `fh_table: array<f32>`; defines FH_COLUMNS,
// FH_ROWS (u32), FH_SHARPNESS_MIN, FH_SHARPNESS_MAX (f32).

const FH_HALF_PI: f32 = 1.57079632679490;

fn fh_fraction(theta: f32, lambda: f32) -> f32 {
    let l = clamp(lambda, FH_SHARPNESS_MIN, FH_SHARPNESS_MAX);
    let row = (log(l) - log(FH_SHARPNESS_MIN)) / (log(FH_SHARPNESS_MAX) - log(FH_SHARPNESS_MIN)) * f32(FH_ROWS - 1u);
    let th = clamp(theta, -FH_HALF_PI, FH_HALF_PI);
    let s = 0.5 * sqrt(max(lambda, 0.0));
    var c = th / FH_HALF_PI;
    if s >= 1e-3 {
        c = tanh(s * th) / tanh(s * FH_HALF_PI);
    }
    let col = (c + 1.0) * 0.5 * f32(FH_COLUMNS - 1u);
    let c0 = min(u32(floor(col)), FH_COLUMNS - 2u);
    let r0 = min(u32(floor(row)), FH_ROWS - 2u);
    let fc = col - f32(c0);
    let fr = row - f32(r0);
    let i = r0 * FH_COLUMNS + c0;
    let top = fh_table[i] * (1.0 - fc) + fh_table[i + 1u] * fc;
    let bottom = fh_table[i + FH_COLUMNS] * (1.0 - fc) + fh_table[i + FH_COLUMNS + 1u] * fc;
    return top * (1.0 - fr) + bottom * fr;
}
