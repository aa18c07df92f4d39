//! The scene file (TOML) and the built-in scenes, one per figure of the
//! paper. The format is documented in the README ("Scene files") and by
//! the built-in scenes under `luts/scenes/`.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use glam::{EulerRot, Mat3, Vec3};
use serde::Deserialize;

use super::environment::{Environment, EquirectMap, Sky, SkyParams};
use super::film::bare_reflectance;
use super::geometry::{Plane, Sphere};
use super::material::{Checker, FilmMaterial, Interior, Material};
use super::mesh::{self, Mesh};
use super::scene::{CameraSpec, Film, Light, Object, Scene, Settings, Shape};
use super::thickness::ThicknessField;
use crate::error::{Error, Result};
use crate::optics::{Stack, MAX_THICKNESS_NM};

/// Built-in scenes: (name, TOML text).
const BUILTIN: [(&str, &str); 6] = [
    (
        "bubbles-uniform",
        include_str!("../../luts/scenes/bubbles-uniform.toml"),
    ),
    (
        "bubbles-noise",
        include_str!("../../luts/scenes/bubbles-noise.toml"),
    ),
    (
        "absorbing-sphere",
        include_str!("../../luts/scenes/absorbing-sphere.toml"),
    ),
    (
        "gain-ring",
        include_str!("../../luts/scenes/gain-ring.toml"),
    ),
    ("blue-gem", include_str!("../../luts/scenes/blue-gem.toml")),
    (
        "two-layer-noise",
        include_str!("../../luts/scenes/two-layer-noise.toml"),
    ),
];

/// Angle nodes of a bare metal's reflectance table: Fresnel of a metal is
/// smooth in cos θ, so linear interpolation over 257 nodes is exact to
/// well below an 8-bit step.
const METAL_TABLE_NODES: usize = 257;

pub fn builtin_names() -> Vec<&'static str> {
    BUILTIN.iter().map(|(n, _)| *n).collect()
}

impl Scene {
    /// A built-in scene by name.
    pub fn builtin(name: &str) -> Option<Result<Scene>> {
        let (n, text) = BUILTIN.iter().find(|(n, _)| *n == name)?;
        Some(Scene::from_toml_str(
            text,
            Path::new("."),
            &format!("built-in scene {n}"),
        ))
    }

    /// Loads a scene file; relative paths inside it are relative to the file.
    pub fn load(path: &Path) -> Result<Scene> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let base = path.parent().unwrap_or(Path::new("."));
        Scene::from_toml_str(&text, base, &path.display().to_string())
    }

    /// A built-in name, or else a path to a scene file.
    pub fn load_named(spec: &str) -> Result<Scene> {
        match Scene::builtin(spec) {
            Some(scene) => scene,
            None if Path::new(spec).exists() => Scene::load(Path::new(spec)),
            None => Err(Error::invalid(
                format!("scene '{spec}'"),
                format!(
                    "neither a file nor a built-in scene ({})",
                    builtin_names().join(", ")
                ),
            )),
        }
    }

    /// Parses scene text; `origin` names it in error messages.
    pub fn from_toml_str(text: &str, base_dir: &Path, origin: &str) -> Result<Scene> {
        let file: SceneFile =
            toml::from_str(text).map_err(|e| crate::error::toml_error(origin, &e, text))?;
        build(file, base_dir, origin)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: Option<String>,
    #[serde(default)]
    render: RenderSection,
    camera: CameraSection,
    #[serde(default)]
    environment: EnvironmentSection,
    #[serde(default)]
    lights: Vec<LightSection>,
    materials: HashMap<String, MaterialSection>,
    objects: Vec<ObjectSection>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct RenderSection {
    width: u32,
    height: u32,
    spp: u32,
    max_depth: u32,
    exposure: f32,
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
struct CameraSection {
    position: [f32; 3],
    look_at: [f32; 3],
    #[serde(default = "y_up")]
    up: [f32; 3],
    fov_deg: f32,
}

fn y_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "snake_case")]
enum EnvironmentSection {
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

fn default_zenith() -> [f32; 3] {
    [0.25, 0.45, 0.9]
}
fn default_horizon() -> [f32; 3] {
    [0.9, 0.92, 0.95]
}
fn default_ground() -> [f32; 3] {
    [0.25, 0.22, 0.2]
}
fn default_sun() -> [f32; 3] {
    [0.3, 0.8, 0.5]
}
fn one() -> f32 {
    1.0
}

impl Default for EnvironmentSection {
    fn default() -> Self {
        toml::from_str("kind = \"sky\"").expect("the default sky parses")
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "snake_case")]
enum LightSection {
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
enum MaterialSection {
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
    },
}

fn first_layer() -> usize {
    1
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CheckerSection {
    albedo: [f32; 3],
    size: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct NoiseSection {
    min_nm: f32,
    max_nm: f32,
    /// The frequency s of d(p) = d_min + (d_max − d_min)·noise(s·p).
    scale: f32,
    #[serde(default)]
    seed: u32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, tag = "shape", rename_all = "snake_case")]
enum ObjectSection {
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
struct TransformSection {
    scale: f32,
    rotate_deg: [f32; 3],
    translate: [f32; 3],
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

fn finite3(origin: &str, what: &str, v: [f32; 3]) -> Result<Vec3> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(Vec3::from(v))
    } else {
        Err(Error::malformed(
            origin,
            format!("{what}: must be finite, got {v:?}"),
        ))
    }
}

/// Absorption coefficients and radiances: a negative one would add light.
fn nonnegative3(origin: &str, what: &str, v: [f32; 3]) -> Result<Vec3> {
    if v.iter().all(|x| x.is_finite() && *x >= 0.0) {
        Ok(Vec3::from(v))
    } else {
        Err(Error::malformed(
            origin,
            format!("{what}: must be finite and ≥ 0, got {v:?}"),
        ))
    }
}

fn positive(origin: &str, what: &str, v: f32) -> Result<f32> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(Error::malformed(
            origin,
            format!("{what}: must be > 0, got {v}"),
        ))
    }
}

fn unit(origin: &str, what: &str, v: [f32; 3]) -> Result<Vec3> {
    let v = finite3(origin, what, v)?;
    if v.length_squared() < 1e-12 {
        return Err(Error::malformed(
            origin,
            format!("{what}: must not be zero"),
        ));
    }
    Ok(v.normalize())
}

/// The deepest reflection/refraction recursion: the tracer recurses on the
/// call stack, and far deeper paths carry no visible light anyway.
pub const MAX_DEPTH: u32 = 64;

/// The widest or tallest image, in pixels: scene files and `irid render
/// --width/--height` alike.
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// The most samples per pixel, in scene files and on the command line alike.
/// Noise falls as 1/√spp: at 4096 it is 1/64 of one sample's, and more only
/// multiplies the render time.
pub const MAX_SPP: u32 = 4096;

fn build(file: SceneFile, base: &Path, origin: &str) -> Result<Scene> {
    let r = &file.render;
    for (field, value, max) in [
        ("render.width", r.width, MAX_IMAGE_SIDE),
        ("render.height", r.height, MAX_IMAGE_SIDE),
        ("render.spp", r.spp, MAX_SPP),
    ] {
        if !(1..=max).contains(&value) {
            return Err(Error::malformed(
                origin,
                format!("{field}: must be between 1 and {max}, got {value}"),
            ));
        }
    }
    if r.max_depth > MAX_DEPTH {
        return Err(Error::malformed(
            origin,
            format!("render.max_depth: must be ≤ {MAX_DEPTH}"),
        ));
    }
    let settings = Settings {
        width: r.width,
        height: r.height,
        spp: r.spp,
        max_depth: r.max_depth,
        exposure: positive(origin, "render.exposure", r.exposure)?,
    };

    let c = &file.camera;
    let camera = CameraSpec {
        position: finite3(origin, "camera.position", c.position)?,
        look_at: finite3(origin, "camera.look_at", c.look_at)?,
        up: unit(origin, "camera.up", c.up)?,
        vfov_deg: c.fov_deg,
    };
    if !(c.fov_deg > 0.0 && c.fov_deg < 180.0) {
        return Err(Error::malformed(
            origin,
            format!("camera.fov_deg: must be in (0, 180), got {}", c.fov_deg),
        ));
    }
    let forward = camera.look_at - camera.position;
    if forward.length_squared() < 1e-12
        || forward.normalize().cross(camera.up).length_squared() < 1e-8
    {
        return Err(Error::malformed(
            origin,
            "camera: look_at must differ from position and not lie along up",
        ));
    }

    let environment = match file.environment {
        EnvironmentSection::Sky {
            zenith,
            horizon,
            ground,
            ground_checker,
            checker_size,
            ground_depth,
            sun_direction,
            sun_radiance,
            sun_radius_deg,
        } => Environment::Sky(Sky::new(SkyParams {
            zenith: nonnegative3(origin, "environment.zenith", zenith)?,
            horizon: nonnegative3(origin, "environment.horizon", horizon)?,
            ground: nonnegative3(origin, "environment.ground", ground)?,
            ground_checker: nonnegative3(
                origin,
                "environment.ground_checker",
                ground_checker.unwrap_or(ground),
            )?,
            checker_size: positive(origin, "environment.checker_size", checker_size)?,
            ground_depth: positive(origin, "environment.ground_depth", ground_depth)?,
            sun_direction: unit(origin, "environment.sun_direction", sun_direction)?,
            sun_radiance: nonnegative3(origin, "environment.sun_radiance", sun_radiance)?,
            sun_radius_deg: if (0.0..=90.0).contains(&sun_radius_deg) {
                sun_radius_deg
            } else {
                return Err(Error::malformed(
                    origin,
                    format!("environment.sun_radius_deg: must be in [0, 90], got {sun_radius_deg}"),
                ));
            },
        })),
        EnvironmentSection::Map { path, intensity } => Environment::Map(EquirectMap::load(
            &base.join(path),
            positive(origin, "environment.intensity", intensity)?,
        )?),
    };

    let mut lights = Vec::new();
    for (i, l) in file.lights.iter().enumerate() {
        let what = |f: &str| format!("lights[{}].{f}", i + 1);
        lights.push(match *l {
            LightSection::Directional { direction, color } => Light::Directional {
                direction: unit(origin, &what("direction"), direction)?,
                color: finite3(origin, &what("color"), color)?,
            },
            LightSection::Point { position, color } => Light::Point {
                position: finite3(origin, &what("position"), position)?,
                color: finite3(origin, &what("color"), color)?,
            },
        });
    }

    // Materials in name order, so film indices do not depend on hashing.
    let mut names: Vec<&String> = file.materials.keys().collect();
    names.sort();
    let mut materials = Vec::new();
    let mut films = Vec::new();
    for name in &names {
        let what = |f: &str| format!("materials.{name}.{f}");
        materials.push(match &file.materials[*name] {
            MaterialSection::Diffuse { albedo, checker } => Material::Diffuse {
                albedo: finite3(origin, &what("albedo"), *albedo)?,
                checker: match checker {
                    Some(c) => Some(Checker {
                        albedo: finite3(origin, &what("checker.albedo"), c.albedo)?,
                        size: positive(origin, &what("checker.size"), c.size)?,
                    }),
                    None => None,
                },
            },
            MaterialSection::Metal { material } => {
                let mut t = toml::Table::new();
                t.insert(
                    "ambient".into(),
                    toml::Value::Table(toml::toml! { n = 1.0 }),
                );
                // A bare name is shorthand for { material = "name" }.
                let substrate = match material {
                    toml::Value::String(name) => {
                        let mut m = toml::Table::new();
                        m.insert("material".into(), toml::Value::String(name.clone()));
                        toml::Value::Table(m)
                    }
                    other => other.clone(),
                };
                t.insert("substrate".into(), substrate);
                let stack = stack_from_table(&t, base, origin, &what("material"))?;
                Material::Metal {
                    reflectance: bare_reflectance(&stack, METAL_TABLE_NODES)
                        .map_err(|e| context(origin, &what("material"), e))?,
                }
            }
            MaterialSection::Dielectric { ior, absorption } => Material::Dielectric {
                ior: positive(origin, &what("ior"), *ior)?,
                absorption: nonnegative3(origin, &what("absorption"), *absorption)?,
            },
            MaterialSection::Film {
                stack,
                layer,
                thickness_nm,
                thickness,
                absorption,
            } => {
                let stack = match stack {
                    toml::Value::String(path) => Stack::load(&base.join(path))
                        .map_err(|e| context(origin, &what("stack"), e))?,
                    toml::Value::Table(t) => stack_from_table(t, base, origin, &what("stack"))?,
                    _ => {
                        return Err(Error::malformed(
                            origin,
                            format!(
                                "{}: a stack file path or an inline stack table",
                                what("stack")
                            ),
                        ))
                    }
                };
                if *layer < 1 || *layer > stack.layers.len() {
                    return Err(Error::malformed(
                        origin,
                        format!(
                            "{}: the stack has {} layer(s), got {layer}",
                            what("layer"),
                            stack.layers.len()
                        ),
                    ));
                }
                let field = match (thickness_nm, thickness) {
                    (Some(_), Some(_)) => {
                        return Err(Error::malformed(
                            origin,
                            format!("materials.{name}: give thickness_nm or thickness, not both"),
                        ))
                    }
                    (Some(d), None) => ThicknessField::Uniform {
                        thickness_nm: film_thickness(origin, &what("thickness_nm"), *d)?,
                    },
                    (None, Some(n)) => {
                        let lo = film_thickness(origin, &what("thickness.min_nm"), n.min_nm)?;
                        let hi = film_thickness(origin, &what("thickness.max_nm"), n.max_nm)?;
                        if hi < lo {
                            return Err(Error::malformed(
                                origin,
                                format!("{}: max_nm < min_nm", what("thickness")),
                            ));
                        }
                        ThicknessField::noise(
                            lo,
                            hi,
                            positive(origin, &what("thickness.scale"), n.scale)?,
                            n.seed,
                        )
                    }
                    (None, None) => ThicknessField::Uniform {
                        thickness_nm: stack.layers[layer - 1].thickness_nm as f32,
                    },
                };
                let real_at_550 = |m: &crate::optics::Material| -> Result<f32> {
                    Ok(m.index_at(550.0)
                        .map_err(|e| context(origin, &what("stack"), e))?
                        .re as f32)
                };
                let outside_ior = real_at_550(&stack.ambient)?;
                let transparent = stack.substrate.is_lossless();
                let inside = if transparent {
                    Some(Interior {
                        ior: real_at_550(&stack.substrate)?,
                        absorption: nonnegative3(origin, &what("absorption"), *absorption)?,
                    })
                } else {
                    None
                };
                let film = films.len();
                films.push(Film {
                    name: (*name).clone(),
                    stack,
                    layer: layer - 1,
                    thickness_range_nm: field.range_nm(),
                    back_side: transparent,
                });
                Material::Film(FilmMaterial {
                    film,
                    thickness: field,
                    outside_ior,
                    inside,
                })
            }
        });
    }

    let material_index = |i: usize, m: &str| -> Result<usize> {
        names.iter().position(|n| *n == m).ok_or_else(|| {
            Error::malformed(
                origin,
                format!(
                    "objects[{}].material: unknown material '{m}' (defined: {})",
                    i + 1,
                    names
                        .iter()
                        .map(|s| s.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )
        })
    };
    let mut objects = Vec::new();
    for (i, o) in file.objects.iter().enumerate() {
        let what = |f: &str| format!("objects[{}].{f}", i + 1);
        let (shape, material) = match o {
            ObjectSection::Sphere {
                material,
                center,
                radius,
            } => (
                Shape::Sphere(Sphere {
                    center: finite3(origin, &what("center"), *center)?,
                    radius: positive(origin, &what("radius"), *radius)?,
                }),
                material,
            ),
            ObjectSection::Plane {
                material,
                point,
                normal,
            } => (
                Shape::Plane(Plane {
                    point: finite3(origin, &what("point"), *point)?,
                    normal: unit(origin, &what("normal"), *normal)?,
                }),
                material,
            ),
            ObjectSection::Torus {
                material,
                major_radius,
                minor_radius,
                transform,
            } => {
                let r = positive(origin, &what("major_radius"), *major_radius)?;
                let m = positive(origin, &what("minor_radius"), *minor_radius)?;
                (
                    mesh_shape(mesh::torus(r, m, 192, 64), transform, origin, &what(""))?,
                    material,
                )
            }
            ObjectSection::Gem {
                material,
                radius,
                transform,
            } => {
                let r = positive(origin, &what("radius"), *radius)?;
                let t = TransformSection {
                    scale: transform.scale * r,
                    rotate_deg: transform.rotate_deg,
                    translate: transform.translate,
                };
                (
                    mesh_shape(mesh::brilliant_gem(), &t, origin, &what(""))?,
                    material,
                )
            }
            ObjectSection::Obj {
                material,
                path,
                transform,
            } => {
                let data = mesh::load_obj(&base.join(path))
                    .map_err(|e| context(origin, &what("path"), e))?;
                (mesh_shape(data, transform, origin, &what(""))?, material)
            }
        };
        objects.push(Object {
            shape,
            material: material_index(i, material)?,
        });
    }
    if objects.is_empty() {
        return Err(Error::malformed(
            origin,
            "objects: the scene has no objects",
        ));
    }
    Ok(Scene {
        name: file.name.unwrap_or_else(|| origin.to_string()),
        settings,
        camera,
        environment,
        lights,
        materials,
        objects,
        films,
    })
}

/// A film thickness: the films are baked or solved, which accept at most
/// [`MAX_THICKNESS_NM`].
fn film_thickness(origin: &str, what: &str, v: f32) -> Result<f32> {
    if v >= 0.0 && f64::from(v) <= MAX_THICKNESS_NM {
        Ok(v)
    } else {
        Err(Error::malformed(
            origin,
            format!("{what}: must be in [0, {MAX_THICKNESS_NM:e}] nm, got {v}"),
        ))
    }
}

/// Prefixes a nested error with the scene file and field it came from.
fn context(origin: &str, what: &str, e: Error) -> Error {
    Error::malformed(origin, format!("{what}: {e}"))
}

fn stack_from_table(t: &toml::Table, base: &Path, origin: &str, what: &str) -> Result<Stack> {
    let text = toml::to_string(t).map_err(|e| Error::malformed(origin, format!("{what}: {e}")))?;
    let stack = Stack::from_toml_str(&text, base, &format!("{origin} ({what})"))
        .map_err(|e| context(origin, what, e))?;
    stack.validate().map_err(|e| context(origin, what, e))?;
    Ok(stack)
}

fn mesh_shape(
    data: mesh::MeshData,
    t: &TransformSection,
    origin: &str,
    what: &str,
) -> Result<Shape> {
    let what = what.trim_end_matches('.');
    let (mut positions, indices, mut normals) = data;
    let scale = positive(origin, &format!("{what}.scale"), t.scale)?;
    let r = finite3(origin, &format!("{what}.rotate_deg"), t.rotate_deg)?;
    let rotation = Mat3::from_euler(
        EulerRot::XYZ,
        r.x.to_radians(),
        r.y.to_radians(),
        r.z.to_radians(),
    );
    let translate = finite3(origin, &format!("{what}.translate"), t.translate)?;
    Mesh::transformed(&mut positions, &mut normals, scale, rotation, translate);
    let mesh = Mesh::new(&positions, &indices, normals).map_err(|e| context(origin, what, e))?;
    Ok(Shape::Mesh(Arc::new(mesh)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_scenes_load_with_the_films_they_need() {
        for name in builtin_names() {
            let scene = Scene::builtin(name).unwrap().unwrap();
            assert!(!scene.films.is_empty(), "{name} has no film");
            for f in &scene.films {
                let (lo, hi) = f.thickness_range_nm;
                assert!(lo <= hi && hi <= 1500.0, "{name}: {lo}..{hi}");
            }
        }
        let gem = Scene::builtin("blue-gem").unwrap().unwrap();
        assert!(
            gem.films[0].back_side,
            "light inside the gem meets the reversed stack"
        );
        let ring = Scene::builtin("gain-ring").unwrap().unwrap();
        assert!(!ring.films[0].back_side, "nothing passes into gold");
        assert!(ring.films[0].stack.layers[0].material.has_gain());
        let two = Scene::builtin("two-layer-noise").unwrap().unwrap();
        assert_eq!((two.settings.width, two.settings.height), (500, 500));
        assert_eq!(
            (two.films[0].stack.layers.len(), two.films[0].layer),
            (2, 1)
        );
        assert!(Scene::builtin("no-such-scene").is_none());
    }

    const MINIMAL: &str = r#"
        [camera]
        position = [0.0, 0.0, 5.0]
        look_at = [0.0, 0.0, 0.0]
        fov_deg = 40.0
        [materials.m]
        kind = "dielectric"
        ior = 1.5
        [[objects]]
        shape = "sphere"
        material = "m"
        center = [0.0, 0.0, 0.0]
        radius = 1.0
    "#;

    fn parse(text: &str) -> Result<Scene> {
        Scene::from_toml_str(text, Path::new("."), "test.toml")
    }

    #[test]
    fn defaults_and_typos() {
        let s = parse(MINIMAL).unwrap();
        assert_eq!(
            (s.settings.width, s.settings.height, s.settings.spp),
            (640, 480, 1)
        );
        assert!(matches!(s.environment, Environment::Sky(_)));
        // A misspelt field is an error naming the line, not silently ignored.
        let e = parse(&MINIMAL.replace("radius = 1.0", "radius = 1.0\nradus = 2.0"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("test.toml") && e.contains("radus") && e.contains("line"),
            "{e}"
        );
        let e = parse(&MINIMAL.replace("fov_deg = 40.0", "fov_deg = 200.0"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("camera.fov_deg"), "{e}");
        let e = parse(&MINIMAL.replace("look_at = [0.0, 0.0, 0.0]", "look_at = [0.0, 0.0, 5.0]"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("camera"), "{e}");
    }

    #[test]
    fn film_fields_are_checked() {
        let film = MINIMAL.replace(
            "kind = \"dielectric\"\n        ior = 1.5",
            "kind = \"film\"\n        stack = { ambient = { n = 1.0 }, substrate = { n = 1.5 }, layers = [{ n = 2.0, thickness_nm = 100.0 }] }",
        );
        let s = parse(&film).unwrap();
        assert_eq!(s.films[0].thickness_range_nm, (100.0, 100.0));
        let bad_layer = film.replace("stack =", "layer = 2\n        stack =");
        let e = parse(&bad_layer).unwrap_err().to_string();
        assert!(e.contains("materials.m.layer"), "{e}");
        let both = film.replace("stack =", "thickness_nm = 50.0\n        thickness = { min_nm = 1.0, max_nm = 2.0, scale = 1.0 }\n        stack =");
        assert!(parse(&both).unwrap_err().to_string().contains("not both"));
        let reversed = film.replace(
            "stack =",
            "thickness = { min_nm = 300.0, max_nm = 200.0, scale = 1.0 }\n        stack =",
        );
        assert!(parse(&reversed)
            .unwrap_err()
            .to_string()
            .contains("max_nm < min_nm"));
        let unknown = film.replace("n = 2.0,", "material = \"unobtainium\",");
        let e = parse(&unknown).unwrap_err().to_string();
        assert!(
            e.contains("materials.m.stack") && e.contains("unobtainium"),
            "{e}"
        );
    }

    /// A syntax error is placed where it is: a value error on line 3 and
    /// one at the very start of line 3 (which counting `lines()` of the
    /// text before it put on line 2).
    #[test]
    fn toml_errors_name_their_line_and_column() {
        let err = |text: &str| {
            Scene::from_toml_str(text, Path::new("."), "s.toml")
                .unwrap_err()
                .to_string()
        };
        let e = err("name = \"x\"\n[render]\nwidth = \"a\"\n");
        assert!(e.contains("line 3, column 9"), "{e}");
        let e = err("[camera]\nposition = [0.0, 1.0\n");
        assert!(e.contains("line 3, column 1"), "{e}");
    }
}
