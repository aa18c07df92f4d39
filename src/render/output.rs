//! Writing images (8-bit sRGB PNG, linear float EXR), always through a
//! temporary file in the target directory and a rename, and comparing two
//! renders in CIEDE2000.

use std::path::Path;

use super::image::Image;
use crate::color::{delta_e2000_rgb, linear_to_srgb8};
use crate::error::{Error, Result};

impl Image {
    /// 8-bit sRGB (clamped) PNG.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        crate::atomic::write_with(path, self.png_writer(path))
    }

    /// Linear-sRGB 32-bit float OpenEXR.
    pub fn write_exr(&self, path: &Path) -> Result<()> {
        crate::atomic::write_with(path, self.exr_writer(path))
    }

    /// The PNG and, if asked, the EXR as one set: both appear or neither
    /// does (a failed EXR leaves no PNG), and the two must be different
    /// files.
    pub fn write_outputs(&self, png: &Path, exr: Option<&Path>) -> Result<()> {
        let mut outputs: Vec<(std::path::PathBuf, crate::atomic::Writer)> =
            vec![(png.to_path_buf(), Box::new(self.png_writer(png)))];
        if let Some(exr) = exr {
            outputs.push((exr.to_path_buf(), Box::new(self.exr_writer(exr))));
        }
        crate::atomic::write_set(outputs)
    }

    /// Writes the PNG at a temporary path (see [`crate::atomic::OutputSet`]);
    /// errors name `path`, the output.
    pub fn png_writer<'a>(&'a self, path: &'a Path) -> impl FnOnce(&Path) -> Result<()> + 'a {
        move |tmp| {
            let mut bytes = Vec::with_capacity(self.pixels.len() * 3);
            for p in &self.pixels {
                bytes.extend_from_slice(&linear_to_srgb8(p.map(f64::from)));
            }
            ::image::save_buffer_with_format(
                tmp,
                &bytes,
                self.width,
                self.height,
                ::image::ExtendedColorType::Rgb8,
                ::image::ImageFormat::Png,
            )
            .map_err(|e| Error::malformed(path, format!("cannot write PNG: {e}")))
        }
    }

    /// Writes the EXR at a temporary path; errors name `path`, the output.
    pub fn exr_writer<'a>(&'a self, path: &'a Path) -> impl FnOnce(&Path) -> Result<()> + 'a {
        move |tmp| {
            let w = self.width as usize;
            exr::prelude::write_rgb_file(tmp, w, self.height as usize, |x, y| {
                let p = self.pixels[y * w + x];
                (p[0], p[1], p[2])
            })
            .map_err(|e| Error::malformed(path, format!("cannot write EXR: {e}")))
        }
    }

    /// The per-pixel CIEDE2000 difference to another image of the same size,
    /// on the displayed colours (clamped to [0, 1] as in the PNG).
    pub fn delta_e2000(&self, other: &Image) -> Result<ColorDifference> {
        if (self.width, self.height) != (other.width, other.height) {
            return Err(Error::invalid(
                "image comparison",
                format!(
                    "sizes differ: {}x{} vs {}x{}",
                    self.width, self.height, other.width, other.height
                ),
            ));
        }
        let clamp = |p: [f32; 3]| p.map(|v| f64::from(v).clamp(0.0, 1.0));
        let mut de: Vec<f64> = self
            .pixels
            .iter()
            .zip(&other.pixels)
            .map(|(a, b)| delta_e2000_rgb(clamp(*a), clamp(*b)))
            .collect();
        de.sort_by(f64::total_cmp);
        let mean = de.iter().sum::<f64>() / de.len().max(1) as f64;
        let rank = crate::stats::p99_index(de.len());
        Ok(ColorDifference {
            mean,
            p99: de[rank],
            max: de[de.len() - 1],
        })
    }
}

/// CIEDE2000 statistics over the pixels of two images.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColorDifference {
    /// Mean CIEDE2000 over all pixels.
    pub mean: f64,
    /// 99th percentile over pixels: the value of rank ⌈0.99·n⌉ in
    /// ascending order.
    pub p99: f64,
    /// Largest CIEDE2000 of any pixel.
    pub max: f64,
}
