//! The scene file as parsed: one type per section, with its defaults.

use std::collections::HashMap;

use serde::Deserialize;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneFile {
    pub(super) name: Option<String>,
    #[serde(default)]
    pub(super) render: RenderSection,
    pub(super) camera: CameraSection,
    #[serde(default)]
    pub(super) environment: EnvironmentSection,
    #[serde(default)]
    pub(super) lights: Vec<LightSection>,
    pub(super) materials: HashMap<String, MaterialSection>,
    pub(super) objects: Vec<ObjectSection>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct RenderSection {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) spp: u32,
    pub(super) max_depth: u32,
    pub(super) exposure: f32,
}

impl Default for RenderSection {
    fn default() -> Self {
        RenderSection {
            width: 640,
            height: 480,
            spp: 1,
            max_depth: 6,
            exposure: 1.0,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraSection {
    pub(super) position: [f32; 3],
    pub(super) look_at: [f32; 3],
    #[serde(default = "y_up")]
    pub(super) up: [f32; 3],
    pub(super) fov_deg: f32,
}

pub(super) fn y_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "snake_case")]
pub(super) enum EnvironmentSection {
    Sky {
        #[serde(default = "default_zenith")]
        zenith: [f32; 3],
        #[serde(default = "default_horizon")]
        horizon: [f32; 3],
        #[serde(default = "default_ground")]
        ground: [f32; 3],
        ground_checker: Option<[f32; 3]>,
        #[serde(default = "one")]
        checker_size: f32,
        #[serde(default = "one")]
        ground_depth: f32,
        #[serde(default = "default_sun")]
        sun_direction: [f32; 3],
        #[serde(default)]
        sun_radiance: [f32; 3],
        #[serde(default)]
        sun_radius_deg: f32,
    },
    Map {
        path: String,
        #[serde(default = "one")]
        intensity: f32,
    },
}

pub(super) fn default_zenith() -> [f32; 3] {
    [0.25, 0.45, 0.9]
}
pub(super) fn default_horizon() -> [f32; 3] {
    [0.9, 0.92, 0.95]
}
pub(super) fn default_ground() -> [f32; 3] {
    [0.25, 0.22, 0.2]
}
pub(super) fn default_sun() -> [f32; 3] {
    [0.3, 0.8, 0.5]
}
pub(super) fn one() -> f32 {
    1.0
}

impl Default for EnvironmentSection {
    fn default() -> Self {
        toml::from_str("kind = \"sky\"").expect("the default sky parses")
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "snake_case")]
pub(super) enum LightSection {
    Directional {
        direction: [f32; 3],
        color: [f32; 3],
    },
    Point {
        position: [f32; 3],
        color: [f32; 3],
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "snake_case")]
pub(super) enum MaterialSection {
    Diffuse {
        albedo: [f32; 3],
        checker: Option<CheckerSection>,
    },
    Metal {
        /// Any material form a stack file accepts: a library name or a table.
        material: toml::Value,
    },
    Dielectric {
        ior: f32,
        #[serde(default)]
        absorption: [f32; 3],
    },
    Film {
        /// A stack file path (relative to the scene file) or an inline stack.
        stack: toml::Value,
        /// The varying layer, counted from 1 at the ambient side.
        #[serde(default = "first_layer")]
        layer: usize,
        thickness_nm: Option<f32>,
        thickness: Option<NoiseSection>,
        #[serde(default)]
        absorption: [f32; 3],
        /// GGX roughness in [0, 1]; 0 is mirror-smooth.
        #[serde(default)]
        roughness: f32,
    },
}

pub(super) fn first_layer() -> usize {
    1
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CheckerSection {
    pub(super) albedo: [f32; 3],
    pub(super) size: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct NoiseSection {
    pub(super) min_nm: f32,
    pub(super) max_nm: f32,
    /// The frequency s of d(p) = d_min + (d_max − d_min)·noise(s·p).
    pub(super) scale: f32,
    #[serde(default)]
    pub(super) seed: u32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, tag = "shape", rename_all = "snake_case")]
pub(super) enum ObjectSection {
    Sphere {
        material: String,
        center: [f32; 3],
        radius: f32,
    },
    Plane {
        material: String,
        point: [f32; 3],
        normal: [f32; 3],
    },
    Torus {
        material: String,
        major_radius: f32,
        minor_radius: f32,
        #[serde(default)]
        transform: TransformSection,
    },
    Gem {
        material: String,
        /// Girdle radius.
        radius: f32,
        #[serde(default)]
        transform: TransformSection,
    },
    Obj {
        material: String,
        path: String,
        #[serde(default)]
        transform: TransformSection,
    },
}

/// Uniform scale, then rotation (XYZ Euler angles), then translation.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct TransformSection {
    pub(super) scale: f32,
    pub(super) rotate_deg: [f32; 3],
    pub(super) translate: [f32; 3],
}

impl Default for TransformSection {
    fn default() -> Self {
        TransformSection {
            scale: 1.0,
            rotate_deg: [0.0; 3],
            translate: [0.0; 3],
        }
    }
}
