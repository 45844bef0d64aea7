//! Serialized FMU states are validated, not only checksummed: a real state is decoded here
//! (by this file's own reading of the layout), one field is edited, the SHA-256 is
//! recomputed, and the instance must refuse it with a message naming the field and what is
//! allowed. Real states of every built-in scene and method are accepted.

use fmi2_model_description::Causality;
use sha2::{Digest, Sha256};
use tensegrity_fmu::fmi::snapshot::Snapshot;
use tensegrity_fmu::fmi::variables::BaseType;
use tensegrity_fmu::fmi::{guid_for, Instance, Mode};

const H: f64 = 1e-3;

/// An instance of a shipped scene, read from a resources folder of its own.
fn scene_text(scene: &str) -> String {
    std::fs::read_to_string(format!("fmu/scenes/{scene}.toml")).expect("scene file")
}

fn instance(scene: &str, tag: &str) -> Instance {
    instance_of(&scene_text(scene), scene, tag)
}

fn instance_of(text: &str, scene: &str, tag: &str) -> Instance {
    let dir = std::env::temp_dir().join(format!(
        "tensegrity-fmu-states-{}-{scene}-{tag}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).expect("resources folder");
    std::fs::write(dir.join("scene.toml"), text).expect("scene.toml");
    let i = Instance::instantiate(tag, &guid_for(text), &dir, false).expect("instantiate");
    std::fs::remove_dir_all(&dir).expect("remove the resources folder");
    i
}

fn vr(i: &Instance, name: &str) -> u32 {
    let v = i.table().variables.iter().find(|v| v.name == name);
    v.unwrap_or_else(|| panic!("no variable {name}"))
        .value_reference
}

/// Initialized with `method` (1–4), `correction` and a stop time of 1 s, a force on node
/// 7, then `steps` steps of [`H`].
fn running(scene: &str, method: i32, correction: bool, steps: usize) -> Instance {
    running_of(&scene_text(scene), scene, method, correction, steps)
}

fn running_of(text: &str, scene: &str, method: i32, correction: bool, steps: usize) -> Instance {
    let mut i = instance_of(text, scene, &format!("m{method}c{}", u8::from(correction)));
    i.setup_experiment(0.0, Some(1.0)).unwrap();
    i.enter_initialization_mode().unwrap();
    let (m, c) = (vr(&i, "solver.method"), vr(&i, "solver.correction"));
    i.set("set", BaseType::Integer, &[m], &[f64::from(method)])
        .unwrap();
    i.set(
        "set",
        BaseType::Boolean,
        &[c],
        &[f64::from(u8::from(correction))],
    )
    .unwrap();
    if i.table().variables.iter().any(|v| v.name == "node[7].fx") {
        let fx = vr(&i, "node[7].fx");
        i.set("set", BaseType::Real, &[fx], &[3.0]).unwrap();
    }
    i.exit_initialization_mode().unwrap();
    for k in 0..steps {
        i.do_step(k as f64 * H, H).unwrap();
    }
    i
}

fn serialized(i: &Instance) -> Vec<u8> {
    i.get_state().unwrap().to_bytes()
}

/// Where each field of a serialized state lies: this test's own reading of the layout
/// (magic, version, GUID, mode, times, stop time, arrays with u64 lengths, flags,
/// parameters, the next step, carried values, friction grips, SHA-256).
#[derive(Debug, Clone, Copy)]
struct Layout {
    mode: usize,
    time: usize,
    state_time: usize,
    has_stop: usize,
    y: (usize, usize),
    force_density: (usize, usize),
    node_force: (usize, usize),
    rest_length: (usize, usize),
    warned: (usize, usize),
    rebuild: usize,
    parameters: (usize, usize),
    h_next: usize,
    carried: (usize, usize),
    grips: (usize, usize),
}

impl Layout {
    fn of(b: &[u8]) -> Self {
        let len = |at: usize| u64::from_le_bytes(b[at..at + 8].try_into().unwrap()) as usize;
        // An array: its length field at `at`, elements of `size` bytes after it.
        let array = |at: &mut usize, size: usize| {
            let n = len(*at);
            let field = (*at, n);
            *at += 8 + n * size;
            field
        };
        let mut at = 12;
        at += 8 + len(at);
        let mode = at;
        let (time, state_time, has_stop) = (at + 1, at + 9, at + 17);
        at += 1 + 8 + 8 + 1 + 8;
        let y = array(&mut at, 8);
        let force_density = array(&mut at, 8);
        let node_force = array(&mut at, 24);
        let rest_length = array(&mut at, 8);
        let warned = array(&mut at, 1);
        let rebuild = at;
        at += 1;
        let parameters = array(&mut at, 8);
        let h_next = at;
        at += 8;
        let carried = array(&mut at, 8);
        let grips = array(&mut at, 8);
        assert_eq!(
            at + 32,
            b.len(),
            "the layout read here covers the whole buffer"
        );
        Self {
            mode,
            time,
            state_time,
            has_stop,
            y,
            force_density,
            node_force,
            rest_length,
            warned,
            rebuild,
            parameters,
            h_next,
            carried,
            grips,
        }
    }
}

fn f64_at(b: &[u8], at: usize) -> f64 {
    f64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}

fn put_f64(b: &mut [u8], at: usize, x: f64) {
    b[at..at + 8].copy_from_slice(&x.to_le_bytes());
}

/// The SHA-256 of everything before it, recomputed as a forger would.
fn resealed(mut b: Vec<u8>) -> Vec<u8> {
    let body = b.len() - 32;
    let digest = Sha256::digest(&b[..body]);
    b[body..].copy_from_slice(&digest);
    b
}

/// Element `k`'s offset in an array field.
fn element((at, _): (usize, usize), k: usize, size: usize) -> usize {
    at + 8 + k * size
}

/// The array at `field` with its last element (of `size` bytes) removed, or with a copy
/// of its first added, and its length field to match.
fn resized(b: &[u8], field: (usize, usize), size: usize, grow: bool) -> Vec<u8> {
    let (at, n) = field;
    let end = at + 8 + n * size;
    let mut out = b[..at].to_vec();
    let n2 = if grow { n + 1 } else { n - 1 };
    out.extend_from_slice(&(n2 as u64).to_le_bytes());
    out.extend_from_slice(&b[at + 8..at + 8 + n.min(n2) * size]);
    if grow {
        out.extend_from_slice(&b[at + 8..at + 8 + size]);
    }
    out.extend_from_slice(&b[end..]);
    out
}

/// Index of a parameter among the state's parameter values (the table's parameter order).
fn parameter_index(i: &Instance, name: &str) -> usize {
    let parameters = i
        .table()
        .variables
        .iter()
        .filter(|v| v.causality == Causality::Parameter);
    parameters
        .map(|v| v.name.as_str())
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no parameter {name}"))
}

/// `b` with parameter value `k` replaced, resealed.
fn with_parameter(b: &[u8], k: usize, value: f64) -> Vec<u8> {
    let l = Layout::of(b);
    let mut b = b.to_vec();
    put_f64(&mut b, element(l.parameters, k, 8), value);
    resealed(b)
}

/// The refusal of `forged` by fmi2DeSerializeFMUstate, and by fmi2SetFMUstate of the same
/// state parsed without the model (a state handed in), each leaving `i` as it was.
fn refusal(i: &mut Instance, forged: &[u8]) -> String {
    let (y, time, mode) = (
        i.simulation().state().clone(),
        i.simulation().time(),
        i.mode(),
    );
    let err = i
        .deserialize_state(forged)
        .expect_err("a forged state is refused");
    assert_eq!(err.status, tensegrity_fmu::fmi::Status::Error);
    let message = err.message;
    assert!(
        message.starts_with("fmi2DeSerializeFMUstate: "),
        "{message}"
    );
    if let Ok(parsed) = Snapshot::from_bytes(&guid(i), forged) {
        let err = i.set_state(&parsed).expect_err("set refuses it too");
        let reason = message.trim_start_matches("fmi2DeSerializeFMUstate: ");
        let reason = reason.split("; nothing was changed").next().unwrap();
        assert!(
            err.message.starts_with("fmi2SetFMUstate: ") && err.message.contains(reason),
            "{} / {reason}",
            err.message
        );
    }
    assert_eq!(i.simulation().state(), &y, "the state was not touched");
    assert_eq!((i.simulation().time(), i.mode()), (time, mode));
    message
}

fn guid(i: &Instance) -> String {
    let b = serialized(i);
    let n = u64::from_le_bytes(b[12..20].try_into().unwrap()) as usize;
    String::from_utf8(b[20..20 + n].to_vec()).unwrap()
}

fn assert_names(message: &str, parts: &[&str]) {
    for p in parts {
        assert!(message.contains(p), "'{p}' is not in: {message}");
    }
}

#[test]
fn real_states_of_every_scene_method_and_correction_setting_are_accepted() {
    for scene in ["prism2", "prism2-elastic", "icosahedron", "tower20"] {
        for method in 1..=4 {
            for correction in [true, false] {
                let mut i = running(scene, method, correction, 60);
                let state = i.get_state().unwrap();
                let back = i.deserialize_state(&state.to_bytes());
                let back = back.unwrap_or_else(|e| panic!("{scene} m{method}: {e:?}"));
                assert_eq!(back, state);
                i.set_state(&back).unwrap();
            }
        }
    }
    // At a negative start time too, which fmi2SetupExperiment allows.
    let mut i = instance("prism2", "negative");
    i.setup_experiment(-2.0, None).unwrap();
    let b = serialized(&i);
    assert_eq!(f64_at(&b, Layout::of(&b).time), -2.0);
    i.deserialize_state(&b).unwrap();
}

#[test]
fn forged_solver_settings_are_refused_naming_the_parameter_and_its_range() {
    let mut i = running("prism2-elastic", 1, true, 10);
    let b = serialized(&i);
    let cases: [(&str, f64, &[&str]); 10] = [
        (
            "solver.method",
            7.0,
            &["solver.method = 7 is not a method (1 = rk4, 2 = dopri5, 3 = rattle, 4 = sdirk3)"],
        ),
        ("solver.method", 0.0, &["solver.method = 0 is not a method"]),
        (
            "solver.correction",
            0.5,
            &["solver.correction = 0.5 is not a Boolean (0 or 1)"],
        ),
        (
            "solver.locate_events",
            2.0,
            &["solver.locate_events = 2 is not a Boolean (0 or 1)"],
        ),
        ("solver.step_size", -1e-3, &["solver.step_size", "must be positive"]),
        ("solver.rtol", -1.0, &["solver.rtol", "must be ≥ 0"]),
        ("solver.max_steps", 0.0, &["solver.max_steps", "at least 1"]),
        (
            "solver.max_steps",
            2.5,
            &["solver.max_steps = 2.5 is not an Integer (a whole number from -2147483648 to 2147483647)"],
        ),
        ("solver.max_steps", 3e9, &["solver.max_steps = 3000000000 is not an Integer"]),
        ("cable[2].stiffness", -5.0, &["cables[2]", "stiffness"]),
    ];
    for (name, value, parts) in cases {
        let forged = with_parameter(&b, parameter_index(&i, name), value);
        let message = refusal(&mut i, &forged);
        assert_names(&message, parts);
    }
    // What fmi2SetInteger refuses is what the state check refuses: one check.
    let m = vr(&i, "solver.method");
    let mut fresh = instance("prism2-elastic", "set");
    let set = fresh.set("fmi2SetInteger", BaseType::Integer, &[m], &[7.0]);
    assert_names(
        &set.unwrap_err().message,
        &["solver.method = 7 is not a method (1 = rk4, 2 = dopri5, 3 = rattle, 4 = sdirk3)"],
    );
    // The untouched buffer is still accepted after all those refusals.
    i.deserialize_state(&b).unwrap();
}

#[test]
fn forged_positions_velocities_and_bar_lengths_are_refused() {
    let mut i = running("prism2", 1, true, 10);
    let b = serialized(&i);
    let l = Layout::of(&b);
    let half = l.y.1 / 2;
    let edit = |k: usize, f: &dyn Fn(f64) -> f64| {
        let mut out = b.clone();
        let at = element(l.y, k, 8);
        put_f64(&mut out, at, f(f64_at(&b, at)));
        resealed(out)
    };
    let far = refusal(&mut i, &edit(0, &|_| 1e300));
    assert_names(&far, &["node[", "position", "is outside ±1e9 m"]);
    let fast = refusal(&mut i, &edit(half, &|_| 1e300));
    assert_names(
        &fast,
        &["node[", "velocity", "is outside ±2.99792458e8 m/s"],
    );
    // Moved by 1 µm: a bar 1e-6 m off its length, far above round-off.
    let moved = refusal(&mut i, &edit(0, &|x| x + 1e-6));
    assert_names(
        &moved,
        &[
            "bar[",
            "m long, but the model's bar is",
            "with solver.correction = 1",
        ],
    );
    // A velocity along a bar: its length would change.
    let along = refusal(&mut i, &edit(half, &|x| x + 1.0));
    assert_names(
        &along,
        &[
            "bar[",
            "ends separate at",
            "a rigid bar's length does not change",
        ],
    );
    // Without the correction a run drifts up to 1% of a length: 1 µm passes, 5 cm not.
    let correction = parameter_index(&i, "solver.correction");
    let uncorrected = |b: Vec<u8>| with_parameter(&b, correction, 0.0);
    i.deserialize_state(&uncorrected(edit(0, &|x| x + 1e-6)))
        .expect("a small drift is what a run without the correction carries");
    let drifted = refusal(&mut i, &uncorrected(edit(0, &|x| x + 0.05)));
    assert_names(&drifted, &["bar[", "with solver.correction = 0"]);
    let nan = refusal(&mut i, &edit(half + 1, &|_| f64::NAN));
    assert_names(&nan, &["state vector", "is NaN, not a finite number"]);
}

#[test]
fn forged_modes_flags_times_and_inputs_are_refused() {
    let mut i = running("prism2", 2, true, 10);
    let b = serialized(&i);
    let l = Layout::of(&b);
    let byte = |at: usize, v: u8| {
        let mut out = b.clone();
        out[at] = v;
        resealed(out)
    };
    let f64s = |edits: &[(usize, f64)]| {
        let mut out = b.clone();
        for &(at, x) in edits {
            put_f64(&mut out, at, x);
        }
        resealed(out)
    };
    assert_names(&refusal(&mut i, &byte(l.mode, 4)), &["mode is Error"]);
    assert_names(&refusal(&mut i, &byte(l.mode, 9)), &["mode code 9"]);
    assert_names(
        &refusal(&mut i, &byte(l.has_stop, 2)),
        &["the stop-time flag is 2, but a Boolean is 0 or 1"],
    );
    assert_names(
        &refusal(&mut i, &byte(l.rebuild, 1)),
        &["pending-rebuild flag is 1 in mode StepComplete"],
    );
    assert_names(
        &refusal(&mut i, &byte(element(l.warned, 0, 1), 2)),
        &["negative-input warning flag 1 is 2, but a Boolean is 0 or 1"],
    );
    let late = f64s(&[(l.time, 3.0), (l.state_time, 3.0)]);
    assert_names(
        &refusal(&mut i, &late),
        &["time = 3 s is past its stop time 1 s"],
    );
    assert_names(&refusal(&mut i, &f64s(&[(l.time, 0.5)])), &["differs"]);
    let input = element(l.force_density, 0, 8);
    assert_names(
        &refusal(&mut i, &f64s(&[(input, f64::INFINITY)])),
        &["force-density inputs: value 1 is inf, not a finite number"],
    );
    let force = element(l.node_force, 1, 8);
    assert_names(
        &refusal(&mut i, &f64s(&[(force, f64::NAN)])),
        &["node-force inputs: value 2 is NaN"],
    );
    assert_names(
        &refusal(&mut i, &f64s(&[(l.h_next, -1e-3)])),
        &["the adaptive method's next step = -0.001 s is not positive (allowed: > 0)"],
    );
}

#[test]
fn arrays_of_the_wrong_length_are_refused_naming_the_array() {
    // rattle carries its last acceleration, so the carried array is not empty.
    let mut i = running("prism2", 3, true, 10);
    let b = serialized(&i);
    let l = Layout::of(&b);
    assert!(l.carried.1 > 0 && l.force_density.1 > 0 && l.warned.1 > 0);
    assert_eq!(l.rest_length.1, 0, "prism2 reels no cable");
    let cases: [((usize, usize), usize, bool, &str); 8] = [
        (
            l.y,
            8,
            false,
            "state vector values (η₂ and η̇₂), this FMU has",
        ),
        (
            l.force_density,
            8,
            false,
            "force-density inputs, this FMU has",
        ),
        (l.node_force, 24, false, "node-force inputs, this FMU has"),
        (
            l.rest_length,
            8,
            true,
            "holds 1 rest-length inputs, this FMU has 0",
        ),
        (
            l.warned,
            1,
            true,
            "negative-input warning flags, this FMU has",
        ),
        (l.parameters, 8, false, "parameter values, this FMU has"),
        (
            l.carried,
            8,
            false,
            "values carried by the integrator; rattle carries 0 or",
        ),
        (
            l.carried,
            8,
            true,
            "values carried by the integrator; rattle carries 0 or",
        ),
    ];
    for (field, size, grow, part) in cases {
        let forged = resealed(resized(&b, field, size, grow));
        assert_names(&refusal(&mut i, &forged), &[part]);
    }
}

#[test]
fn an_instance_refusing_a_state_carries_on_as_if_never_asked() {
    let mut twin = running("prism2-elastic", 1, true, 10);
    let mut i = running("prism2-elastic", 1, true, 10);
    let b = serialized(&i);
    let forged = with_parameter(&b, parameter_index(&i, "solver.method"), 7.0);
    refusal(&mut i, &forged);
    for k in 10..20 {
        i.do_step(k as f64 * H, H).unwrap();
        twin.do_step(k as f64 * H, H).unwrap();
    }
    assert_eq!(i.simulation().state(), twin.simulation().state());
    assert_eq!(i.mode(), Mode::StepComplete);
}

#[test]
fn friction_grips_travel_with_the_state_and_forged_ones_are_refused() {
    // At 0.6 s the icosahedron has landed across its step: some ends stick, some slide.
    let steps = (0.6 / H) as usize;
    let mut i = running("icosahedron-step", 2, true, steps);
    let b = serialized(&i);
    let l = Layout::of(&b);
    let modes: Vec<f64> = (0..l.grips.1 / 4)
        .map(|k| f64_at(&b, element(l.grips, 4 * k, 8)))
        .collect();
    let count = |mode: f64| modes.iter().filter(|&&m| m == mode).count();
    let (held, sliding) = (count(1.0), count(2.0));
    println!("{} grips, {held} sticking, {sliding} sliding", modes.len());
    assert_eq!(modes.len(), 6 * 2 * 2, "one grip per bar end and shape");
    assert!(
        held >= 1 && sliding >= 1,
        "saved while ends stick and slide: {modes:?}"
    );
    let at = element(l.grips, 0, 8);
    let mut forged = b.clone();
    put_f64(&mut forged, at, 3.0);
    assert_names(
        &refusal(&mut i, &resealed(forged)),
        &["friction grip 1 has mode 3 (allowed: 0 free, 1 stick, 2 slip)"],
    );
    assert_names(
        &refusal(&mut i, &resealed(resized(&b, l.grips, 8, false))),
        &["corrupt state: 95 friction-grip values, not four per grip"],
    );
    // Restored into a twin, the state carries on exactly as the original.
    let mut twin = running("icosahedron-step", 2, true, 0);
    twin.set_state(&twin.deserialize_state(&b).unwrap())
        .unwrap();
    for k in steps..steps + 200 {
        i.do_step(k as f64 * H, H).unwrap();
        twin.do_step(k as f64 * H, H).unwrap();
    }
    assert_eq!(i.simulation().state(), twin.simulation().state());
    assert_eq!(i.simulation().grips(), twin.simulation().grips());
}

#[test]
fn a_grip_forged_where_friction_does_not_stick_is_refused() {
    // The same drop with the step's friction regularised: no end grips the step.
    let text = scene_text("icosahedron-step") + "friction_model = \"regularized\"\n";
    let steps = (0.6 / H) as usize;
    let mut i = running_of(&text, "icosahedron-step-regularized", 2, true, steps);
    let b = serialized(&i);
    let l = Layout::of(&b);
    // Grip 3 is bar 1's first end on the second shape, the step.
    assert_eq!(f64_at(&b, element(l.grips, 8, 8)), 0.0, "free on the step");
    let mut forged = b.clone();
    put_f64(&mut forged, element(l.grips, 8, 8), 1.0);
    assert_names(
        &refusal(&mut i, &resealed(forged)),
        &[
            "friction grip 3 holds where nothing grips",
            "terrain[2] with friction_model = \"regularized\"",
        ],
    );
    // The state as saved is taken.
    let mut twin = running_of(&text, "icosahedron-step-regularized", 2, true, 0);
    twin.set_state(&twin.deserialize_state(&b).unwrap())
        .unwrap();
}
