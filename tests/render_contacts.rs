//! Contact points and forces: the listing of a state against closed forms (a bar resting
//! across two boxes, crossed bars, a bar on the `[ground]`), the dots and arrows they add
//! to a picture, the page's and ParaView's contact data, and `--contacts` refused where it
//! cannot be drawn. Figures are printed (run with `--nocapture`).

mod cli_support;

use cli_support::{run, temp};
use tensegrity_fmu::dynamics::contact_points::{ContactKind, ContactPoint};
use tensegrity_fmu::render::picture::{self, contacts::CONTACT, Style, PNG_SIZE};
use tensegrity_fmu::render::view::project;
use tensegrity_fmu::render::Frames;
use tensegrity_fmu::{Model, Scene, Simulation};

const G: f64 = 9.81;

fn sim(toml: &str) -> Simulation {
    Simulation::new(Model::new(&Scene::from_toml_str(toml).unwrap()).unwrap())
}

/// A 2 kg bar of radius 5 cm from x = −1 to 1 across two boxes (tops at z = 0.5, edges at
/// x = ±0.4 and ±0.8), as in tests/terrain.rs.
fn bar_across_two_boxes() -> String {
    let boxes: String = [-0.6, 0.6]
        .iter()
        .map(|x| {
            format!(
                "[[terrain]]\nkind = \"box\"\ncenter = [{x}, 0.0, 0.25]\nsize = [0.4, 1.0, 0.5]\n\
                 stiffness = 1e5\ndamping = 400.0\nfriction = 0.5\n"
            )
        })
        .collect();
    format!(
        "name = \"bar\"\nnodes = [[-1.0, 0.0, 0.6], [1.0, 0.0, 0.6]]\n\
         bars = [{{ nodes = [1, 2], mass = 2.0, radius = 0.05 }}]\n\
         gravity = [0.0, 0.0, -{G}]\n{boxes}"
    )
}

fn vertical_sum(contacts: &[ContactPoint]) -> f64 {
    contacts.iter().map(|c| c.force.z).sum()
}

#[test]
fn a_bar_across_two_boxes_lists_its_four_edge_contacts_carrying_its_weight() {
    let mut s = sim(&bar_across_two_boxes());
    s.advance_to(3.0).unwrap();
    s.refresh();
    let mut contacts = s.contact_points();
    contacts.sort_by(|a, b| a.point.x.total_cmp(&b.point.x));
    // The bar rests on the four top edges it crosses, a quarter of m g on each.
    let m_g = 2.0 * G;
    let xs: Vec<f64> = contacts.iter().map(|c| c.point.x).collect();
    let sum = vertical_sum(&contacts);
    println!("edge contacts at x = {xs:?}, vertical forces sum {sum} N (m g = {m_g} N)");
    assert_eq!(contacts.len(), 4, "{contacts:?}");
    for (c, (x, shape)) in contacts
        .iter()
        .zip([(-0.8, 0), (-0.4, 0), (0.4, 1), (0.8, 1)])
    {
        assert!((c.point.x - x).abs() < 1e-9, "{c:?} at x = {x}");
        assert_eq!(c.kind, ContactKind::Terrain { bar: 0, shape });
        // On the capsule's surface, pressed m g / (4 k) into the top.
        let depth = m_g / (4.0 * 1e5);
        assert!((c.point.z - (0.5 - depth)).abs() < 1e-7, "{c:?}");
        assert!((c.force.z - m_g / 4.0).abs() < 1e-6 * m_g, "{c:?}");
    }
    assert!((sum - m_g).abs() < 1e-6 * m_g, "{sum}");
}

#[test]
fn crossed_bars_at_rest_list_one_pair_with_opposite_forces() {
    // A pinned bar along x; a free 1.5 kg bar along y lies across it (tests/collisions.rs).
    let (m, ra, rb, k) = (1.5, 0.03, 0.02, 2e5);
    let z = ra + rb;
    let mut s = sim(&format!(
        "name = \"crossed\"\nnodes = [[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, -0.5, {z}], [0.0, 0.5, {z}]]\n\
         fixed = [1, 2]\n\
         bars = [{{ nodes = [1, 2], mass = 1.0, radius = {ra} }}, {{ nodes = [3, 4], mass = {m}, radius = {rb} }}]\n\
         gravity = [0.0, 0.0, -{G}]\n\
         collisions = {{ stiffness = {k}, damping = 300.0, friction = 0.5 }}\n"
    ));
    s.advance_to(2.0).unwrap();
    s.refresh();
    let contacts = s.contact_points();
    println!("{contacts:?}");
    assert_eq!(contacts.len(), 2, "one pair, a point on each bar");
    let (lower, upper) = (&contacts[0], &contacts[1]);
    assert_eq!(lower.kind, ContactKind::Collision { bar: 0, other: 1 });
    assert_eq!(upper.kind, ContactKind::Collision { bar: 1, other: 0 });
    assert_eq!(lower.force, -upper.force);
    assert!((upper.force.z - m * G).abs() < 1e-6 * m * G, "{upper:?}");
    // Each on its own surface, where the axes cross: the pinned bar's top, the free bar's
    // bottom pressed m g / k into it.
    assert!((lower.point - nalgebra::Vector3::new(0.0, 0.0, ra)).norm() < 1e-9);
    let depth = m * G / k;
    assert!((upper.point.z - (ra - depth)).abs() < 1e-8, "{upper:?}");
    assert!(upper.point.xy().norm() < 1e-8, "{upper:?}");
}

#[test]
fn a_bar_on_the_ground_lists_its_two_nodes() {
    let mut s = sim(&format!(
        "name = \"lying\"\nnodes = [[0.0, 0.0, 0.02], [1.0, 0.0, 0.02]]\n\
         bars = [{{ nodes = [1, 2], mass = 3.0, radius = 0.02 }}]\n\
         gravity = [0.0, 0.0, -{G}]\n\
         [ground]\nheight = 0.0\nstiffness = 1e5\ndamping = 500.0\n"
    ));
    s.advance_to(2.0).unwrap();
    s.refresh();
    let contacts = s.contact_points();
    println!("{contacts:?}");
    assert_eq!(contacts.len(), 2);
    for (c, node) in contacts.iter().zip(0..) {
        assert_eq!(c.kind, ContactKind::Ground { node });
        // The node's sphere's lowest point, pressed m g / (2 k) into the ground.
        let expected = s.node_position(node) - nalgebra::Vector3::new(0.0, 0.0, 0.02);
        assert!((c.point - expected).norm() < 1e-12, "{c:?}");
        assert!((c.point.z + 3.0 * G / 2e5).abs() < 1e-7, "{c:?}");
    }
    assert!((vertical_sum(&contacts) - 3.0 * G).abs() < 1e-6 * 3.0 * G);
}

/// The bar across two boxes at rest, recorded with its contacts.
fn resting_bar_frames() -> Frames {
    let mut s = sim(&bar_across_two_boxes());
    Frames::record_contacts(&mut s, &[2.0]).unwrap()
}

#[test]
fn a_picture_with_contacts_shows_dots_and_arrows_there() {
    let frames = resting_bar_frames();
    let style = Style::new(30.0, 20.0, false);
    let without = Frames {
        contacts: Vec::new(),
        ..frames.clone()
    };
    let (with_png, without_png) = (temp("contacts.png"), temp("no-contacts.png"));
    picture::write_png(&frames, 0, &style, &with_png).unwrap();
    picture::write_png(&without, 0, &style, &without_png).unwrap();
    let (a, b) = (
        image::open(&with_png).unwrap().to_rgb8(),
        image::open(&without_png).unwrap().to_rgb8(),
    );
    let fit = picture::fit(&frames, PNG_SIZE, &style);
    let ink = [CONTACT.0, CONTACT.1, CONTACT.2];
    let count = |img: &image::RgbImage, (x, y): (i32, i32), r: i32| {
        let mut n = 0;
        for py in (y - r).max(0)..=(y + r) {
            for px in (x - r).max(0)..=(x + r) {
                n += usize::from(img.get_pixel(px as u32, py as u32).0 == ink);
            }
        }
        n
    };
    let scale = frames.contact_scale().unwrap();
    for c in &frames.contacts[0] {
        let at = fit.to_pixel(project([c.point.x, c.point.y, c.point.z], 30.0, 20.0));
        // Along the arrow, halfway to its tip (past the dot).
        let tip = c.point + c.force * scale.metres_per_newton * 0.6;
        let mid = fit.to_pixel(project([tip.x, tip.y, tip.z], 30.0, 20.0));
        let (dot, arrow) = (count(&a, at, 3), count(&a, mid, 2));
        println!("contact at pixel {at:?}: {dot} dot pixels, {arrow} arrow pixels at {mid:?}");
        assert!(dot >= 9 && arrow >= 3, "{c:?}");
        assert_eq!(count(&b, at, 3) + count(&b, mid, 2), 0);
    }
}

#[test]
fn the_page_and_paraview_carry_the_contacts() {
    let frames = resting_bar_frames();
    let json = tensegrity_fmu::render::html::embedded_json(&frames);
    let data: serde_json::Value = serde_json::from_str(&json).unwrap();
    let max = data["contacts"]["max_force"].as_f64().unwrap();
    println!("page: largest contact force {max} N");
    assert!((max - 2.0 * G / 4.0).abs() < 1e-5, "{max}");
    let plain = Frames {
        contacts: Vec::new(),
        ..frames.clone()
    };
    let json = tensegrity_fmu::render::html::embedded_json(&plain);
    assert!(json.contains("\"contacts\":null"), "{json}");

    let pvd = temp("contacts.pvd");
    tensegrity_fmu::render::vtk::write_pvd(&frames, &pvd).unwrap();
    let collection = std::fs::read_to_string(&pvd).unwrap();
    assert!(
        collection.contains("part=\"2\" file=\"contacts_vtp/contacts_contacts_0000.vtp\""),
        "{collection}"
    );
    let vtp = pvd.with_file_name("contacts_vtp/contacts_contacts_0000.vtp");
    let vtp = std::fs::read_to_string(vtp).unwrap();
    assert!(
        vtp.contains("NumberOfPoints=\"4\" NumberOfVerts=\"4\""),
        "{vtp}"
    );
    assert!(
        vtp.contains("Name=\"force\" NumberOfComponents=\"3\""),
        "{vtp}"
    );
}

#[test]
fn contacts_are_refused_for_a_csv_and_a_scene_where_nothing_touches() {
    let png = temp("refused.png");
    let png = png.to_str().unwrap();
    let args = [
        "render",
        "prism2",
        "--contacts",
        "--csv",
        "run.csv",
        "-o",
        png,
    ];
    let (ok, _, e) = run(&args);
    println!("{e}");
    assert!(!ok);
    assert_eq!(e.trim().lines().count(), 1, "{e}");
    assert!(
        e.contains("--contacts")
            && e.contains("CSV holds no contact")
            && e.contains("drop --csv to simulate"),
        "{e}"
    );
    let (ok, _, e) = run(&["render", "prism2", "--contacts", "-o", png]);
    println!("{e}");
    assert!(
        !ok && e.contains("--contacts") && e.contains("nothing can touch"),
        "{e}"
    );
    assert!(!std::path::Path::new(png).exists());
}
