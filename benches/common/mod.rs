//! What the render benches share: the paper's timing scene
//! (`two-layer-noise`) in the variants they compare, and the cache its
//! tables are baked into.

use std::path::PathBuf;

use irid::render::material::Material;
use irid::render::thickness::ThicknessField;
use irid::render::Scene;

/// Each bench binary uses its own part.
#[allow(dead_code)]
pub struct TimingScene {
    /// Where the benches' tables are cached (apart from `luts/cache`).
    pub cache: PathBuf,
    /// The scene as shipped: a noise-thickness film on glass.
    pub scene: Scene,
    /// The same film at one thickness: no noise, so no thickness grid.
    pub uniform: Scene,
    /// The film replaced by bare glass: the cost of iridescence is
    /// measured against it.
    pub plain: Scene,
}

impl TimingScene {
    pub fn load() -> TimingScene {
        let scene = Scene::builtin("two-layer-noise").unwrap().unwrap();
        let mut uniform = scene.clone();
        for m in uniform.materials.iter_mut() {
            if let Material::Film(f) = m {
                f.thickness = ThicknessField::Uniform {
                    thickness_nm: 350.0,
                };
            }
        }
        let plain = scene.without_films(|_| unreachable!("two-layer-noise coats glass"));
        TimingScene {
            cache: PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("render-bench-cache"),
            scene,
            uniform,
            plain,
        }
    }
}
