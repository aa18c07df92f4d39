//! What the gradient tests share: stacks of constant indices and the four
//! parts (Rs, Rp, Ts, Tp) of a response and of its derivatives.

use num_complex::Complex64 as C64;

use irid::optics::gradient::ResponseGradient;
use irid::optics::{Layer, Material, Response, Stack};

pub fn constant(n: C64) -> Material {
    Material::constant(n.re, n.im)
}

/// A stack of constant indices (ambient, layers, substrate) and thicknesses.
pub fn stack_of(indices: &[C64], thicknesses_nm: &[f64]) -> Stack {
    Stack {
        ambient: constant(indices[0]),
        layers: thicknesses_nm
            .iter()
            .zip(&indices[1..])
            .map(|(&d, &n)| Layer::new(constant(n), d))
            .collect(),
        substrate: constant(indices[indices.len() - 1]),
    }
}

/// Rs, Rp, Ts, Tp.
pub fn parts(r: &Response) -> [f64; 4] {
    [r.rs, r.rp, r.ts, r.tp]
}

/// The derivatives of Rs, Rp, Ts, Tp by parameter `layer`.
pub fn gradient_parts(g: &ResponseGradient, layer: usize) -> [f64; 4] {
    [g.rs[layer], g.rp[layer], g.ts[layer], g.tp[layer]]
}
