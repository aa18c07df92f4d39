//! One chart's axes: the closed-form map from (thickness, cos θ) to the
//! chart coordinates (x, y) in [0, 1]² that `shaders/irid_film.wgsl`
//! computes, and its inverse (where the chart's nodes sit). The atlas
//! (`atlas.rs`) places x, y on the chart's texel centres.

use serde::{Deserialize, Serialize};

/// A chart's domain, warps and node counts, in f64 here; the shader gets
/// them as f32 ([`Mapping::params_f32`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Mapping {
    /// The thickness range (nm) the u axis spans.
    pub thickness_min_nm: f64,
    /// See `thickness_min_nm`.
    pub thickness_max_nm: f64,
    /// The cos θ range the v axis spans.
    pub cos_min: f64,
    /// See `cos_min`.
    pub cos_max: f64,
    /// The cos θ towards which angle nodes crowd quadratically: a
    /// dense-side stack's critical angle strictly inside the range, or
    /// `cos_min` to crowd them towards grazing incidence; −1 for nodes
    /// uniform in cos θ.
    pub cos_crit: f64,
    /// The mapped angle coordinate of `cos_crit`, k / (size_v − 1): always
    /// on a node (0 when crowding towards grazing or uniform).
    pub y_crit: f64,
    /// Texels along u (thickness).
    pub size_u: usize,
    /// Texels along v (angle).
    pub size_v: usize,
    /// 1: thickness nodes uniform; 2: node i at t_min + span · (i / (N − 1))²,
    /// crowding towards t_min (where a thin film at grazing incidence
    /// changes fastest).
    pub thickness_power: f64,
}

/// How the angle nodes are placed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AngleWarp {
    /// Uniform in cos θ.
    Uniform,
    /// Crowding quadratically towards cos_min (grazing incidence).
    Grazing,
    /// A node exactly on this cos θ (a dense-side stack's critical angle),
    /// crowding quadratically towards it from both sides. Uniform when it
    /// is not strictly inside the range.
    Critical(f64),
}

impl Mapping {
    /// The mapping of a `size_u` × `size_v` texture over a domain. With a
    /// critical cos θ strictly inside the cos range (and at least three
    /// angle nodes) the node k nearest its share of the range,
    /// (c_crit − c_min) / (c_max − c_min), is put on it: both sides then
    /// have the same node spacing far from it.
    pub fn new(
        thickness_nm: (f64, f64),
        cos_theta: (f64, f64),
        thickness_power: f64,
        angle: AngleWarp,
        size_u: usize,
        size_v: usize,
    ) -> Mapping {
        let (c0, c1) = cos_theta;
        let (cos_crit, y_crit) = match angle {
            AngleWarp::Critical(cc) if cc > c0 && cc < c1 && size_v >= 3 => {
                let intervals = (size_v - 1) as f64;
                let share = (cc - c0) / (c1 - c0);
                let k = (share * intervals).round().clamp(1.0, intervals - 1.0);
                (cc, k / intervals)
            }
            AngleWarp::Grazing if c1 > c0 => (c0, 0.0),
            _ => (-1.0, 0.0),
        };
        let thickness_power = if thickness_nm.1 > thickness_nm.0 {
            thickness_power
        } else {
            1.0
        };
        Mapping {
            thickness_min_nm: thickness_nm.0,
            thickness_max_nm: thickness_nm.1,
            cos_min: c0,
            cos_max: c1,
            cos_crit,
            y_crit,
            size_u: size_u.max(1),
            size_v: size_v.max(1),
            thickness_power,
        }
    }

    /// The angle warp this mapping uses.
    pub fn angle_warp(&self) -> AngleWarp {
        if self.cos_crit < 0.0 {
            AngleWarp::Uniform
        } else if self.cos_crit == self.cos_min && self.y_crit == 0.0 {
            AngleWarp::Grazing
        } else {
            AngleWarp::Critical(self.cos_crit)
        }
    }

    /// The same domain and warp with `size_u` × `size_v` texels. Doubling
    /// the intervals (2N − 1 nodes) keeps every node and the critical one.
    pub fn resized(&self, size_u: usize, size_v: usize) -> Mapping {
        let mut m = Mapping::new(
            (self.thickness_min_nm, self.thickness_max_nm),
            (self.cos_min, self.cos_max),
            self.thickness_power,
            self.angle_warp(),
            size_u,
            size_v,
        );
        // A refinement by a whole factor keeps the critical node where it
        // was (rounding anew could move it by one fine interval), so the
        // coarse nodes are exactly every factor-th fine node.
        let (old, new) = (self.size_v.saturating_sub(1), size_v.saturating_sub(1));
        if m.cos_crit == self.cos_crit && self.y_crit > 0.0 && old > 0 && new % old == 0 {
            let k = (self.y_crit * old as f64).round() * (new / old) as f64;
            m.y_crit = k / new as f64;
        }
        m
    }

    /// The thickness at texel column i.
    pub fn thickness_at(&self, i: usize) -> f64 {
        if self.size_u <= 1 {
            return self.thickness_min_nm;
        }
        let x = i as f64 / (self.size_u - 1) as f64;
        let span = self.thickness_max_nm - self.thickness_min_nm;
        if i + 1 == self.size_u {
            self.thickness_max_nm
        } else if self.thickness_power == 2.0 {
            self.thickness_min_nm + span * x * x
        } else {
            self.thickness_min_nm + span * x
        }
    }

    /// cos θ at texel row j: the inverse of the angle warp.
    pub fn cos_at(&self, j: usize) -> f64 {
        if self.size_v <= 1 {
            return self.cos_min;
        }
        let y = j as f64 / (self.size_v - 1) as f64;
        if j + 1 == self.size_v {
            return self.cos_max;
        }
        if self.cos_crit < 0.0 {
            return self.cos_min + (self.cos_max - self.cos_min) * y;
        }
        let yc = self.y_crit;
        if y >= yc {
            let s = (y - yc) / (1.0 - yc);
            self.cos_crit + (self.cos_max - self.cos_crit) * s * s
        } else {
            let s = (yc - y) / yc;
            self.cos_crit - (self.cos_crit - self.cos_min) * s * s
        }
    }

    /// The thickness nodes (nm), one per texel column.
    pub fn thickness_nodes(&self) -> Vec<f64> {
        (0..self.size_u).map(|i| self.thickness_at(i)).collect()
    }

    /// The cos θ nodes, one per texel row.
    pub fn cos_nodes(&self) -> Vec<f64> {
        (0..self.size_v).map(|j| self.cos_at(j)).collect()
    }

    /// The chart's first two vec4 in the shader's uniform array, as f32
    /// (docs/gpu.md): thickness range, cos θ range, then cos_crit, y_crit,
    /// thickness power and a reserved 0.
    pub fn params_f32(&self) -> [f32; 8] {
        [
            self.thickness_min_nm as f32,
            self.thickness_max_nm as f32,
            self.cos_min as f32,
            self.cos_max as f32,
            self.cos_crit as f32,
            self.y_crit as f32,
            self.thickness_power as f32,
            0.0,
        ]
    }
}

/// The chart coordinates (x, y) in [0, 1]² of (thickness, cos θ) under a
/// chart's parameters ([`Mapping::params_f32`]): `irid_film_uv` of the
/// shader up to the chart's rectangle, operation for operation in f32.
pub fn chart_xy(params: &[f32; 8], thickness_nm: f32, cos_theta: f32) -> [f32; 2] {
    let [t0, t1, c0, c1, cc, yc, tp, _] = *params;
    let t_span = t1 - t0;
    let mut x = if t_span > 0.0 {
        ((thickness_nm - t0) / t_span).clamp(0.0, 1.0)
    } else {
        0.0
    };
    if tp > 1.5 {
        x = x.sqrt();
    }
    let c = cos_theta.max(c0).min(c1);
    let y = if cc < 0.0 {
        let c_span = c1 - c0;
        if c_span > 0.0 {
            (c - c0) / c_span
        } else {
            0.0
        }
    } else if c >= cc {
        yc + (1.0 - yc) * ((c - cc) / (c1 - cc)).sqrt()
    } else {
        yc - yc * ((cc - c) / (cc - c0)).sqrt()
    };
    [x, y]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nodes_land_on_whole_steps_of_the_chart_coordinates() {
        for (power, angle) in [
            (1.0, AngleWarp::Uniform),
            (2.0, AngleWarp::Critical(0.4)),
            (2.0, AngleWarp::Grazing),
            (1.0, AngleWarp::Critical(0.02)),
        ] {
            let critical = (power, angle);
            let m = Mapping::new((10.0, 900.0), (0.05, 1.0), power, angle, 37, 53);
            for i in 0..m.size_u {
                for j in 0..m.size_v {
                    let (t, c) = (m.thickness_at(i), m.cos_at(j));
                    let xy = chart_xy(&m.params_f32(), t as f32, c as f32);
                    let want = [
                        i as f32 / (m.size_u - 1) as f32,
                        j as f32 / (m.size_v - 1) as f32,
                    ];
                    assert!((xy[0] - want[0]).abs() < 2e-6, "{critical:?} x {i}");
                    assert!((xy[1] - want[1]).abs() < 2e-5, "{critical:?} y {j}");
                }
            }
        }
    }

    #[test]
    fn the_critical_angle_is_a_node_and_nodes_increase() {
        let m = Mapping::new(
            (0.0, 1.0),
            (0.0174, 1.0),
            2.0,
            AngleWarp::Critical(0.7303),
            2,
            65,
        );
        let nodes = m.cos_nodes();
        assert!(nodes.windows(2).all(|w| w[0] < w[1]));
        assert!(nodes.contains(&0.7303));
        // Doubling the intervals keeps every node, the critical one included.
        let fine = m.resized(3, 129);
        for (j, &c) in nodes.iter().enumerate() {
            assert!((fine.cos_at(2 * j) - c).abs() < 1e-15);
        }
        // Outside the range (or a critical angle at its edge) the warp is linear.
        let edge = Mapping::new((0.0, 1.0), (0.5, 1.0), 1.0, AngleWarp::Critical(0.5), 2, 65);
        assert_eq!(edge.cos_crit, -1.0);
        // Crowding towards grazing: quadratic from cos_min, and the warp
        // survives resizing.
        let g = Mapping::new((0.0, 1.0), (0.1, 1.0), 2.0, AngleWarp::Grazing, 5, 5);
        let want = [0.1, 0.15625, 0.325, 0.60625, 1.0];
        assert!(g
            .cos_nodes()
            .iter()
            .zip(want)
            .all(|(a, b)| (a - b).abs() < 1e-15));
        assert_eq!(g.resized(9, 9).angle_warp(), AngleWarp::Grazing);
        assert_eq!(g.thickness_nodes(), [0.0, 0.0625, 0.25, 0.5625, 1.0]);
    }
}
