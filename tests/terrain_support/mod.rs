//! Terrain scenes shared by the contact tests.
#![allow(dead_code)]

use tensegrity_fmu::{Model, Scene, Simulation};

pub const G: f64 = 9.81;

pub fn sim(toml: &str) -> Simulation {
    let scene = Scene::from_toml_str(toml).unwrap();
    Simulation::new(Model::new(&scene).unwrap())
}

/// A one-stage prism (3 bars of 1 kg, elastic cables) with its base on the plane through
/// the origin of outward normal `n = (−sin θ, 0, cos θ)`, and that plane as terrain
/// (`kind` plane, or a heightfield with the same surface), with `extra` keys on the shape.
pub fn prism_on_slope(theta: f64, mu: f64, heightfield: bool, extra: &str) -> Simulation {
    damped_prism_on_slope(theta, mu, heightfield, extra, 0.0)
}

/// [`prism_on_slope`] with cable damping `c` (N·s/m), so that it comes to rest.
pub fn damped_prism_on_slope(
    theta: f64,
    mu: f64,
    heightfield: bool,
    extra: &str,
    c: f64,
) -> Simulation {
    Simulation::new(Model::new(&prism_scene(theta, mu, heightfield, extra, c)).unwrap())
}

/// The scene of [`damped_prism_on_slope`].
pub fn prism_scene(theta: f64, mu: f64, heightfield: bool, extra: &str, c: f64) -> Scene {
    let mut scene = tensegrity_fmu::scene::tower_scene(1, Some(2000.0), "prism");
    if c > 0.0 {
        scene
            .cables
            .iter_mut()
            .for_each(|cable| cable.damping = Some(c));
    }
    scene.fixed.clear();
    scene.force_inputs.clear();
    scene.gravity = Some([0.0, 0.0, -G]);
    let (s, c) = theta.sin_cos();
    let (k, depth) = (1e5, 3.0 * G / 3.0 / 1e5);
    for p in &mut scene.nodes {
        // Rotate about y by −θ so that the base lies in the slope, sunk to its static depth.
        let (x, z) = (p[0], p[2] - depth);
        *p = [c * x - s * z, p[1], s * x + c * z];
    }
    let shape = if heightfield {
        // h(x, y) = x tan θ on a grid wide enough for the whole run.
        let (nx, ny, dx) = (41, 9, 0.25);
        let rows: Vec<String> = (0..ny)
            .map(|_| {
                let row: Vec<String> = (0..nx)
                    .map(|i| format!("{:?}", (-8.0 + i as f64 * dx) * theta.tan()))
                    .collect();
                format!("[{}]", row.join(", "))
            })
            .collect();
        format!(
            "kind = \"heightfield\"\norigin = [-8.0, -1.0]\nspacing = [{dx}, 0.25]\nheights = [{}]\n",
            rows.join(", ")
        )
    } else {
        format!(
            "kind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [{:?}, 0.0, {c:?}]\n",
            -s
        )
    };
    let text = format!(
        "{}\n[[terrain]]\n{shape}stiffness = {k}\ndamping = 300.0\nfriction = {mu}\n{extra}",
        scene.to_toml_string()
    );
    Scene::from_toml_str(&text).unwrap()
}
