//! The cases' luminaires, written as IES LM-63 text and read by the library's parser (as a
//! user's file would be): a Lambertian distribution and an isotropic one.

use radiosity::photometry::{parse_bytes, Photometry};
use std::fmt::Write as _;
use std::sync::Arc;

/// Vertical-angle step of the Lambertian table, degrees. The parser interpolates linearly in
/// γ; between two tabulated angles γ ± Δ/2 the chord of cos γ is exactly cos γ · cos(Δ/2)
/// at its middle, so the intensity is low by at most 1 − cos(Δ/2) = 3.8 × 10⁻⁵ at 1°.
pub(crate) const LAMBERT_STEP_DEG: f64 = 1.0;

/// The relative error bound of the tabulated Lambertian law, 1 − cos(Δ/2).
#[cfg(test)]
pub(crate) fn lambert_table_error() -> f64 {
    1.0 - (0.5 * LAMBERT_STEP_DEG).to_radians().cos()
}

/// IES LM-63-2002 text of a rotationally symmetric type C distribution `f(γ)` candela on the
/// vertical angles `gammas`, absolute photometry, with a luminous opening `width × length`
/// metres (0 × 0: a point).
fn ies(gammas: &[f64], f: impl Fn(f64) -> f64, width: f64, length: f64) -> String {
    let mut s =
        String::from("IESNA:LM-63-2002\n[TEST] CIE 171:2006 test case luminaire\nTILT=NONE\n");
    let _ = writeln!(
        s,
        "1 -1 1 {} 1 1 2 {width:?} {length:?} 0\n1 1 0",
        gammas.len()
    );
    let block = |s: &mut String, values: &[f64]| {
        for chunk in values.chunks(10) {
            let words: Vec<String> = chunk.iter().map(|v| format!("{v:?}")).collect();
            let _ = writeln!(s, "{}", words.join(" "));
        }
    };
    block(&mut s, gammas);
    block(&mut s, &[0.0]);
    let candela: Vec<f64> = gammas.iter().map(|&g| f(g)).collect();
    block(&mut s, &candela);
    s
}

fn parse(text: &str, name: &str) -> Arc<Photometry> {
    Arc::new(parse_bytes(text.as_bytes(), name).expect("the cases' IES text is well formed"))
}

/// I(γ) = `i0` cos γ below the horizontal, 0 above: a Lambertian emitter facing its nadir,
/// tabulated every [`LAMBERT_STEP_DEG`]; a luminous opening `width × length` metres.
pub(crate) fn lambertian(i0: f64, width: f64, length: f64) -> Arc<Photometry> {
    let n = (180.0 / LAMBERT_STEP_DEG).round() as usize;
    let gammas: Vec<f64> = (0..=n).map(|k| k as f64 * LAMBERT_STEP_DEG).collect();
    let f = |g: f64| {
        if g < 90.0 {
            i0 * g.to_radians().cos()
        } else {
            0.0
        }
    };
    parse(&ies(&gammas, f, width, length), "lambertian.ies")
}

/// The same `i` candela in every direction, a point.
pub(crate) fn isotropic(i: f64) -> Arc<Photometry> {
    parse(&ies(&[0.0, 90.0, 180.0], |_| i, 0.0, 0.0), "isotropic.ies")
}
