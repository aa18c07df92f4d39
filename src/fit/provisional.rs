//! Central differences standing in for `optics::gradient` until that
//! module lands (same signature as its `solve_stack_grid_with_gradient`).

use crate::error::Result;
use crate::optics::{Response, StackGrid};

pub struct GradientGrid {
    pub wavelengths: usize,
    pub angles: usize,
    pub response: Vec<Response>,
    pub d_rs: Vec<f64>,
    pub d_rp: Vec<f64>,
    pub d_ts: Vec<f64>,
    pub d_tp: Vec<f64>,
}

pub fn solve_stack_grid_with_gradient(
    grid: &StackGrid,
    thicknesses_nm: &[f64],
    cos_theta0: &[f64],
) -> Result<GradientGrid> {
    let layers = thicknesses_nm.len();
    let (w, a) = (grid.wavelengths_nm().len(), cos_theta0.len());
    let mut response = vec![Response::default(); w * a];
    grid.solve_spectrum(thicknesses_nm, cos_theta0[0], &mut response[..]);
    let mut out = GradientGrid {
        wavelengths: w,
        angles: a,
        response: response.clone(),
        d_rs: vec![0.0; layers * w * a],
        d_rp: vec![0.0; layers * w * a],
        d_ts: vec![0.0; layers * w * a],
        d_tp: vec![0.0; layers * w * a],
    };
    assert_eq!(a, 1);
    let (mut up, mut down) = (response.clone(), response);
    for l in 0..layers {
        let h = 1e-4;
        let mut t = thicknesses_nm.to_vec();
        t[l] += h;
        grid.solve_spectrum(&t, cos_theta0[0], &mut up);
        t[l] -= 2.0 * h;
        grid.solve_spectrum(&t, cos_theta0[0], &mut down);
        for i in 0..w {
            let k = l * w + i;
            out.d_rs[k] = (up[i].rs - down[i].rs) / (2.0 * h);
            out.d_rp[k] = (up[i].rp - down[i].rp) / (2.0 * h);
            out.d_ts[k] = (up[i].ts - down[i].ts) / (2.0 * h);
            out.d_tp[k] = (up[i].tp - down[i].tp) / (2.0 * h);
        }
    }
    Ok(out)
}
