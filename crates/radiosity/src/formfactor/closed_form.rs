//! Closed-form configuration factors from Howell's catalogue ("A Catalog of Radiation Heat
//! Transfer Configuration Factors", J. R. Howell), the references of the form-factor tests and
//! of `radiosity bench --form-factors`.

use std::f64::consts::PI;

/// C-11: directly opposed parallel rectangles a × b at distance c.
pub fn parallel_rectangles(a: f64, b: f64, c: f64) -> f64 {
    let (x, y) = (a / c, b / c);
    let (x2, y2) = (x * x, y * y);
    2.0 / (PI * x * y)
        * (((1.0 + x2) * (1.0 + y2) / (1.0 + x2 + y2)).sqrt().ln()
            + x * (1.0 + y2).sqrt() * (x / (1.0 + y2).sqrt()).atan()
            + y * (1.0 + x2).sqrt() * (y / (1.0 + x2).sqrt()).atan()
            - x * x.atan()
            - y * y.atan())
}

/// C-14: perpendicular rectangles with a common edge of length l, the first w wide, the second
/// h high; F from the first to the second.
pub fn perpendicular_rectangles(l: f64, w: f64, h: f64) -> f64 {
    let (hh, ww) = (h / l, w / l);
    let (h2, w2) = (hh * hh, ww * ww);
    let a = (1.0 + w2) * (1.0 + h2) / (1.0 + w2 + h2);
    let b = (w2 * (1.0 + w2 + h2) / ((1.0 + w2) * (w2 + h2))).powf(w2);
    let c = (h2 * (1.0 + h2 + w2) / ((1.0 + h2) * (h2 + w2))).powf(h2);
    1.0 / (PI * ww)
        * (ww * (1.0 / ww).atan() + hh * (1.0 / hh).atan()
            - (h2 + w2).sqrt() * (1.0 / (h2 + w2).sqrt()).atan()
            + 0.25 * (a * b * c).ln())
}

/// C-41: parallel coaxial discs of radii r1 (from) and r2 (to) at distance h.
pub fn coaxial_discs(r1: f64, r2: f64, h: f64) -> f64 {
    let (a, b) = (r1 / h, r2 / h);
    let x = 1.0 + (1.0 + b * b) / (a * a);
    0.5 * (x - (x * x - 4.0 * (b / a).powi(2)).sqrt())
}

/// From a differential area to a parallel `a × b` rectangle at distance `c`, the area's normal
/// through one corner of the rectangle (Howell's catalogue, B-3).
pub fn point_parallel_rectangle(a: f64, b: f64, c: f64) -> f64 {
    let (x, y) = (a / c, b / c);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * std::f64::consts::PI)
}
