//! Seven scenes with one element pushed to an extreme, of the kinds a fuzzer found running
//! for minutes under dopri5 (which shrinks its step to the fastest time scale): each names
//! the element that sets that time scale. The tests and `bench work` use them.

use super::{builtin, GroundSpec, LoadSpec, PrestressSpec, Scene};

/// An extreme scene: the scene and the key that makes it extreme.
pub struct Extreme {
    /// The scene (the default solver, dopri5); its name says what is extreme.
    pub scene: Scene,
    /// The scene key that sets the fastest time scale, as the refusal names it.
    pub key: &'static str,
}

/// The seven extreme scenes, from prism2-elastic (prism2 for the prestress one).
pub fn extreme_scenes() -> Vec<Extreme> {
    let make = |from: &str, name: &str, key: &'static str, change: &dyn Fn(&mut Scene)| {
        let mut scene = builtin(from).expect("a built-in scene");
        scene.name = name.into();
        scene.description = None;
        change(&mut scene);
        Extreme { scene, key }
    };
    let elastic = "prism2-elastic";
    vec![
        make(elastic, "stiff-cable", "cables[4]", &|s| {
            s.cables[3].stiffness = Some(5e14)
        }),
        make(elastic, "heavy-gravity", "gravity", &|s| {
            s.gravity = Some([0.0, 0.0, -1e15])
        }),
        make(elastic, "huge-load", "loads[1]", &|s| {
            s.loads = vec![LoadSpec::Constant {
                node: 7,
                force: [1e12, 0.0, 0.0],
            }]
        }),
        // Unpinned, standing on the ground under gravity.
        make(elastic, "stiff-ground", "ground.stiffness", &|s| {
            s.fixed.clear();
            s.gravity = Some([0.0, 0.0, -9.81]);
            // The defaults: at z = 0, no damping, no friction.
            s.ground = Some(toml::from_str::<GroundSpec>("stiffness = 1e16").expect("a ground"));
        }),
        make(elastic, "tiny-masses", "1e-15 kg", &|s| {
            s.bars.iter_mut().for_each(|b| b.mass = 1e-15)
        }),
        make(elastic, "huge-damping", "cables[7].damping", &|s| {
            // Under gravity, so that the damped cable moves.
            s.gravity = Some([0.0, 0.0, -9.81]);
            s.cables[6].damping = Some(1e12);
        }),
        make("prism2", "tight-prestress", "force density", &|s| {
            s.prestress = Some(PrestressSpec { min_tension: 1e14 })
        }),
    ]
}
