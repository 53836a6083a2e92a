//! Isolines of a lattice field by marching squares (Lorensen & Cline 1987, in two
//! dimensions): each square of four valued nodes is cut where the level crosses its edges,
//! the crossing placed by linear interpolation along the edge, t = (L − E₀)/(E₁ − E₀); a
//! square with two opposite corners above the level (a saddle) is resolved by the mean of its
//! corners (Nielson & Hamann's asymptotic decider simplified to the centre value). A square
//! with a missing node (outside the grid) is skipped, so lines end at the grid's edge and
//! around its holes. The segments are joined through their shared edges into polylines.

use super::lattice::Field;
use std::collections::HashMap;

/// An isoline in the drawing plane; a closed one's last point repeats its first.
#[derive(Clone, Debug, PartialEq)]
pub struct Polyline {
    /// The points in order, scene units along the drawing axes.
    pub points: Vec<[f64; 2]>,
    /// Whether it closes on itself (else it ends at the edge of the field's values).
    pub closed: bool,
}

impl Polyline {
    /// Length along the points.
    pub fn length(&self) -> f64 {
        self.points
            .windows(2)
            .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
            .sum()
    }
}

/// The isolines of `field` at `level` (a node is above it when its value ≥ `level`), in a
/// fixed order: open lines first, from the first square they cross, then closed ones.
pub fn isolines(field: &Field, level: f64) -> Vec<Polyline> {
    let nu = field.nu;
    if nu < 2 || field.nv < 2 {
        return Vec::new();
    }
    // An edge's key: 2 × node for the edge to the node's right, 2 × node + 1 to the one above.
    let h = |i: usize, j: usize| 2 * (j * nu + i) as u64;
    let v = |i: usize, j: usize| 2 * (j * nu + i) as u64 + 1;
    let mut segments: Vec<[u64; 2]> = Vec::new();
    for j in 0..field.nv - 1 {
        for i in 0..nu - 1 {
            let c = [
                field.value(i, j),
                field.value(i + 1, j),
                field.value(i + 1, j + 1),
                field.value(i, j + 1),
            ];
            if c.iter().any(|x| !x.is_finite()) {
                continue;
            }
            let above = c.map(|x| x >= level);
            // Edges: bottom (corners 0–1), right (1–2), top (3–2), left (0–3).
            let edges = [h(i, j), v(i + 1, j), h(i, j + 1), v(i, j)];
            let ends = [(0, 1), (1, 2), (3, 2), (0, 3)];
            let crossed: Vec<usize> = (0..4)
                .filter(|&e| above[ends[e].0] != above[ends[e].1])
                .collect();
            match crossed.len() {
                2 => segments.push([edges[crossed[0]], edges[crossed[1]]]),
                4 => {
                    // A saddle: corners 0 and 2 on one side, 1 and 3 on the other. The centre
                    // joins the pair on its side; the lines cut off the other two corners.
                    let centre_above = c.iter().sum::<f64>() / 4.0 >= level;
                    if centre_above == above[0] {
                        // 0 and 2 joined: cut off corner 1 (bottom, right), corner 3 (top, left).
                        segments.push([edges[0], edges[1]]);
                        segments.push([edges[2], edges[3]]);
                    } else {
                        // 1 and 3 joined: cut off corner 0 (left, bottom), corner 2 (right, top).
                        segments.push([edges[3], edges[0]]);
                        segments.push([edges[1], edges[2]]);
                    }
                }
                _ => {}
            }
        }
    }
    // The crossing point on an edge.
    let point = |key: u64| -> [f64; 2] {
        let n = (key / 2) as usize;
        let (i, j) = (n % nu, n / nu);
        let (i1, j1) = if key % 2 == 0 { (i + 1, j) } else { (i, j + 1) };
        let (e0, e1) = (field.value(i, j), field.value(i1, j1));
        let t = ((level - e0) / (e1 - e0)).clamp(0.0, 1.0);
        let (p0, p1) = (field.node(i, j), field.node(i1, j1));
        [p0[0] + t * (p1[0] - p0[0]), p0[1] + t * (p1[1] - p0[1])]
    };
    let mut at: HashMap<u64, Vec<usize>> = HashMap::new();
    for (s, seg) in segments.iter().enumerate() {
        for &k in seg {
            at.entry(k).or_default().push(s);
        }
    }
    let mut used = vec![false; segments.len()];
    let mut lines = Vec::new();
    let mut walk = |start: usize, from: u64, used: &mut Vec<bool>| {
        let mut points = vec![point(from)];
        let (mut seg, mut key) = (start, from);
        loop {
            used[seg] = true;
            key = if segments[seg][0] == key {
                segments[seg][1]
            } else {
                segments[seg][0]
            };
            points.push(point(key));
            match at[&key].iter().find(|&&s| !used[s]) {
                Some(&s) => seg = s,
                None => break,
            }
        }
        let closed = key == from && points.len() > 2;
        lines.push(Polyline { points, closed });
    };
    // Open lines from their ends, then the loops left.
    for s in 0..segments.len() {
        if used[s] {
            continue;
        }
        if let Some(&end) = segments[s].iter().find(|k| at[k].len() == 1) {
            walk(s, end, &mut used);
        }
    }
    for s in 0..segments.len() {
        if !used[s] {
            walk(s, segments[s][0], &mut used);
        }
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    /// E = 100 − r² about an off-lattice centre: the isoline at L is the circle of radius
    /// √(100 − L); every extracted point lies within one lattice step of it (the interpolation
    /// error of r² along an edge is at most h²/8 over a gradient of 2r, far less), the circle
    /// comes back closed with no angular gap wider than two steps, and a hole in the lattice
    /// opens it.
    #[test]
    fn a_radial_field_gives_circles() {
        let h = 0.1;
        let centre = [0.031, -0.017];
        let mut f = Field::empty([-2.0, -2.0], [h, h], 41, 41);
        for j in 0..41 {
            for i in 0..41 {
                let p = f.node(i, j);
                let r2 = (p[0] - centre[0]).powi(2) + (p[1] - centre[1]).powi(2);
                f.values[j * 41 + i] = 100.0 - r2;
            }
        }
        for level in [99.5, 98.0, 97.0] {
            let r = (100.0f64 - level).sqrt();
            let lines = isolines(&f, level);
            assert_eq!(lines.len(), 1, "level {level}");
            let line = &lines[0];
            assert!(line.closed);
            let mut angles = Vec::new();
            for p in &line.points {
                let d = (p[0] - centre[0]).hypot(p[1] - centre[1]);
                assert!((d - r).abs() < h, "level {level}: {p:?} at {d}, circle {r}");
                assert!(
                    (d - r).abs() < h * h / (4.0 * r),
                    "level {level}: {d} vs {r}"
                );
                angles.push((p[1] - centre[1]).atan2(p[0] - centre[0]));
            }
            angles.sort_by(f64::total_cmp);
            let mut gap = angles[0] + std::f64::consts::TAU - angles[angles.len() - 1];
            for w in angles.windows(2) {
                gap = gap.max(w[1] - w[0]);
            }
            assert!(gap * r < 2.0 * h, "level {level}: angular gap {gap}");
            // The length: the chords' deficit and the points' offset, under 0.5 %.
            let (l, c) = (line.length(), std::f64::consts::TAU * r);
            assert!((l - c).abs() < 0.005 * c, "level {level}: {l} vs {c}");
        }
        // A level whose circle (r = 2.5) leaves the lattice: open arcs ending at its edge.
        for line in isolines(&f, 93.75) {
            assert!(!line.closed);
            for p in [line.points[0], *line.points.last().unwrap()] {
                let edge = (p[0].abs() - 2.0).abs().min((p[1].abs() - 2.0).abs());
                assert!(edge < 1e-9, "{p:?}");
            }
        }
        // A missing node on the circle of radius 1 opens it.
        let k = 20 * 41 + 30; // node (1.0, 0.0)
        f.values[k] = f64::NAN;
        let lines = isolines(&f, 99.0);
        assert_eq!(lines.len(), 1);
        assert!(!lines[0].closed);
        // E = x·y is linear along every lattice edge: its crossings are exact; two arms.
        let mut s = Field::empty([-1.0, -1.0], [0.25, 0.25], 9, 9);
        for j in 0..9 {
            for i in 0..9 {
                let p = s.node(i, j);
                s.values[j * 9 + i] = p[0] * p[1];
            }
        }
        let lines = isolines(&s, 0.01);
        assert_eq!(lines.len(), 2);
        for line in &lines {
            for p in &line.points {
                assert!((p[0] * p[1] - 0.01).abs() < 1e-12, "{p:?}");
            }
        }
        // Saddles: corners 0 and 2 above 0.5, 1 and 3 below; the centre's mean decides which
        // pair the lines cut off.
        for (values, cut) in [
            ([1.0, 0.0, 1.0, 0.2], [[1.0, 0.0], [0.0, 1.0]]),
            ([1.0, 0.0, 0.8, 0.0], [[0.0, 0.0], [1.0, 1.0]]),
        ] {
            let sq = Field {
                origin: [0.0, 0.0],
                step: [1.0, 1.0],
                nu: 2,
                nv: 2,
                values: vec![values[0], values[1], values[3], values[2]],
            };
            let lines = isolines(&sq, 0.5);
            assert_eq!(lines.len(), 2);
            for line in &lines {
                let m = [
                    0.5 * (line.points[0][0] + line.points[1][0]),
                    0.5 * (line.points[0][1] + line.points[1][1]),
                ];
                assert!(
                    cut.iter()
                        .any(|c| (m[0] - c[0]).abs() < 0.5 && (m[1] - c[1]).abs() < 0.5),
                    "{values:?}: {line:?}"
                );
            }
        }
    }
}
