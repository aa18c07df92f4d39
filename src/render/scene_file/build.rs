//! From parsed sections to the scene: one function per section, and per
//! material and shape kind, each checking its fields (pbrt's per-type
//! `Create(parameters)` is the model).

use std::path::Path;
use std::sync::Arc;

use glam::{EulerRot, Mat3, Vec3};

use super::sections::{
    CameraSection, EnvironmentSection, LightSection, MaterialSection, NoiseSection, ObjectSection,
    RenderSection, SceneFile, TransformSection,
};
use super::{MAX_DEPTH, MAX_IMAGE_SIDE, MAX_SPP, METAL_TABLE_NODES};
use crate::error::{Error, Result};
use crate::optics::{Stack, MAX_THICKNESS_NM};
use crate::render::compensation::Compensation;
use crate::render::environment::{Environment, EquirectMap, Sky, SkyParams};
use crate::render::film::bare_reflectance;
use crate::render::geometry::{Plane, Sphere};
use crate::render::material::{Checker, FilmMaterial, Interior, Material};
use crate::render::mesh::{self, Mesh};
use crate::render::scene::{CameraSpec, Film, Light, Object, Scene, Settings, Shape};
use crate::render::thickness::ThicknessField;

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

/// Builds a scene from its parsed file, section by section: each section's
/// function checks its fields and names the first bad one. The sections are
/// checked in file order (render, camera, environment, lights, materials,
/// objects), so a file with several errors reports the first.
pub(super) fn build(file: SceneFile, base: &Path, origin: &str) -> Result<Scene> {
    let settings = render_settings(&file.render, origin)?;
    let camera = camera(&file.camera, origin)?;
    let environment = environment(file.environment, base, origin)?;
    let lights = file
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| light(l, &format!("lights[{}]", i + 1), origin))
        .collect::<Result<Vec<_>>>()?;
    // Materials in name order, so film indices do not depend on hashing.
    let mut names: Vec<&String> = file.materials.keys().collect();
    names.sort();
    let mut materials = Vec::new();
    let mut films = Vec::new();
    for name in &names {
        let section = &file.materials[*name];
        materials.push(material(name, section, base, origin, &mut films)?);
    }
    let mut objects = Vec::new();
    for (i, o) in file.objects.iter().enumerate() {
        let (shape, material) = object(o, &format!("objects[{}]", i + 1), base, origin)?;
        objects.push(Object {
            shape,
            material: material_index(&names, i, material, origin)?,
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

/// The `[render]` section: image size, samples and depth within the limits.
fn render_settings(r: &RenderSection, origin: &str) -> Result<Settings> {
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
    Ok(Settings {
        width: r.width,
        height: r.height,
        spp: r.spp,
        max_depth: r.max_depth,
        exposure: positive(origin, "render.exposure", r.exposure)?,
    })
}

/// The `[camera]` section: a look-at camera whose view direction is neither
/// zero nor along `up`.
fn camera(c: &CameraSection, origin: &str) -> Result<CameraSpec> {
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
    Ok(camera)
}

/// The `[environment]` section: the procedural sky or an equirectangular
/// map (its path relative to the scene file).
fn environment(section: EnvironmentSection, base: &Path, origin: &str) -> Result<Environment> {
    Ok(match section {
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
    })
}

/// One `[[lights]]` entry; `at` names it in messages (`lights[2]`).
fn light(l: &LightSection, at: &str, origin: &str) -> Result<Light> {
    let what = |f: &str| format!("{at}.{f}");
    Ok(match *l {
        LightSection::Directional { direction, color } => Light::Directional {
            direction: unit(origin, &what("direction"), direction)?,
            color: finite3(origin, &what("color"), color)?,
        },
        LightSection::Point { position, color } => Light::Point {
            position: finite3(origin, &what("position"), position)?,
            color: finite3(origin, &what("color"), color)?,
        },
    })
}

/// One `[materials.NAME]` entry. A film material also appends its film to
/// `films` (the renderer bakes or solves one table per film).
fn material(
    name: &str,
    section: &MaterialSection,
    base: &Path,
    origin: &str,
    films: &mut Vec<Film>,
) -> Result<Material> {
    let what = |f: &str| format!("materials.{name}.{f}");
    Ok(match section {
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
        MaterialSection::Metal { material } => metal(material, &what("material"), base, origin)?,
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
            roughness,
        } => {
            let stack = film_stack(stack, *layer, name, base, origin)?;
            let field = thickness_field(
                name,
                (*thickness_nm, thickness.as_ref()),
                stack.layers[layer - 1].thickness_nm,
                origin,
            )?;
            crate::rough::check_roughness(&what("roughness"), f64::from(*roughness))
                .map_err(|e| Error::malformed(origin, e.to_string()))?;
            let mut material = film(name, stack, *layer, field, *absorption, origin, films)?;
            if let Material::Film(f) = &mut material {
                f.alpha = roughness * roughness;
                let eta = f.inside.map(|i| f64::from(i.ior / f.outside_ior));
                f.compensation = Compensation::new(f64::from(*roughness), eta);
            }
            material
        }
    })
}

/// A metal: the bare substrate `material` (a library name or a material
/// table) under air, its reflectance tabulated over the angle.
fn metal(material: &toml::Value, what: &str, base: &Path, origin: &str) -> Result<Material> {
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
    let stack = stack_from_table(&t, base, origin, what)?;
    Ok(Material::Metal {
        reflectance: bare_reflectance(&stack, METAL_TABLE_NODES)
            .map_err(|e| context(origin, what, e))?,
    })
}

/// A film material's stack (a file path relative to the scene file, or an
/// inline table), with `layer` (counted from 1) one of its layers.
fn film_stack(
    stack: &toml::Value,
    layer: usize,
    name: &str,
    base: &Path,
    origin: &str,
) -> Result<Stack> {
    let what = |f: &str| format!("materials.{name}.{f}");
    let stack = match stack {
        toml::Value::String(path) => {
            Stack::load(&base.join(path)).map_err(|e| context(origin, &what("stack"), e))?
        }
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
    if layer < 1 || layer > stack.layers.len() {
        return Err(Error::malformed(
            origin,
            format!(
                "{}: the stack has {} layer(s), got {layer}",
                what("layer"),
                stack.layers.len()
            ),
        ));
    }
    Ok(stack)
}

/// A film's thickness over the surface: `thickness_nm` (uniform), a
/// `thickness` noise table, or else the stack's own thickness of the layer
/// (`stack_nm`).
fn thickness_field(
    name: &str,
    (thickness_nm, noise): (Option<f32>, Option<&NoiseSection>),
    stack_nm: f64,
    origin: &str,
) -> Result<ThicknessField> {
    let what = |f: &str| format!("materials.{name}.{f}");
    Ok(match (thickness_nm, noise) {
        (Some(_), Some(_)) => {
            return Err(Error::malformed(
                origin,
                format!("materials.{name}: give thickness_nm or thickness, not both"),
            ))
        }
        (Some(d), None) => ThicknessField::Uniform {
            thickness_nm: film_thickness(origin, &what("thickness_nm"), d)?,
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
            thickness_nm: stack_nm as f32,
        },
    })
}

/// A film material: appends the film (its stack, varying layer and the
/// thickness range its table must cover) to `films`. A lossless substrate
/// is transparent: the film then has a back side and the object an interior.
fn film(
    name: &str,
    stack: Stack,
    layer: usize,
    field: ThicknessField,
    absorption: [f32; 3],
    origin: &str,
    films: &mut Vec<Film>,
) -> Result<Material> {
    let what = |f: &str| format!("materials.{name}.{f}");
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
            absorption: nonnegative3(origin, &what("absorption"), absorption)?,
        })
    } else {
        None
    };
    let film = films.len();
    films.push(Film {
        name: name.to_string(),
        stack,
        layer: layer - 1,
        thickness_range_nm: field.range_nm(),
        back_side: transparent,
    });
    Ok(Material::Film(FilmMaterial {
        film,
        thickness: field,
        outside_ior,
        inside,
        alpha: 0.0,
        compensation: Compensation::default(),
    }))
}

/// The index of object `i`'s material among the sorted material `names`.
fn material_index(names: &[&String], i: usize, m: &str, origin: &str) -> Result<usize> {
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
}

/// One `[[objects]]` entry's shape and material name; `at` names it in
/// messages (`objects[3]`).
fn object<'a>(
    o: &'a ObjectSection,
    at: &str,
    base: &Path,
    origin: &str,
) -> Result<(Shape, &'a String)> {
    let what = |f: &str| format!("{at}.{f}");
    Ok(match o {
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
            let data =
                mesh::load_obj(&base.join(path)).map_err(|e| context(origin, &what("path"), e))?;
            (mesh_shape(data, transform, origin, &what(""))?, material)
        }
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
