//! FMU state snapshots (`fmi2GetFMUstate`) and their serialized form: a magic, a format
//! version and the GUID, then the state in little-endian fields, then a SHA-256 of it all.
//! A buffer from another FMU, another version, with a wrong length or a bad checksum is
//! rejected, and so is one whose fields the model does not allow (see `check`). Only
//! parameters travel, never geometry or topology.

mod check;

use nalgebra::Vector3;
use sha2::{Digest, Sha256};

use super::state::Core;
use super::variables::Variable;
use super::Mode;
use crate::contact::Grip;
use crate::sim::{Simulation, State};
use fmi2_model_description::Causality;

const MAGIC: &[u8; 8] = b"TNSGSTAT";
const VERSION: u32 = 4;
/// A SHA-256 of everything before it closes the buffer, so corruption is caught.
const DIGEST_LEN: usize = 32;

/// Everything needed to return an instance to a point in its history.
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot {
    guid: String,
    mode: Mode,
    time: f64,
    stop_time: Option<f64>,
    state: State,
    force_density: Vec<f64>,
    node_force: Vec<Vector3<f64>>,
    rest_length: Vec<f64>,
    warned_negative: Vec<bool>,
    rebuild: bool,
    /// Values of the parameter variables, in table order.
    parameters: Vec<f64>,
    /// The adaptive method's next trial step, s.
    h_next: f64,
    /// Values the integrator carries to the next step.
    carried: Vec<f64>,
    /// The friction grips, four values each (mode, anchor).
    grips: Vec<f64>,
}

impl Snapshot {
    pub(super) fn take(guid: &str, core: &Core) -> Self {
        Self {
            guid: guid.to_string(),
            mode: core.mode,
            time: core.time,
            stop_time: core.stop_time,
            state: core.sim.state().clone(),
            force_density: core.sim.inputs.force_density.clone(),
            node_force: core.sim.inputs.node_force.clone(),
            rest_length: core.sim.inputs.rest_length.clone(),
            warned_negative: core.warned_negative.clone(),
            rebuild: core.rebuild,
            parameters: parameter_variables(core)
                .map(|v| core.read(v.binding))
                .collect(),
            h_next: core.sim.carried().0,
            carried: core.sim.carried().1,
            grips: core
                .sim
                .grips()
                .iter()
                .flat_map(|g| g.to_values())
                .collect(),
        }
    }

    /// The grips the values hold (checked when they were read).
    pub(super) fn grips(&self) -> Vec<Grip> {
        self.grips
            .as_chunks::<4>()
            .0
            .iter()
            .map(|v| Grip::from_values(*v).unwrap_or_default())
            .collect()
    }

    /// Applies the state to `core` after checking it, or leaves `core` as it was.
    pub(super) fn restore(&self, guid: &str, core: &mut Core) -> Result<(), String> {
        if self.guid != guid {
            return Err(format!(
                "the state belongs to another FMU (GUID {})",
                self.guid
            ));
        }
        let scene = self.check(core)?;
        let mut sim = if scene == core.scene {
            core.sim.clone()
        } else {
            // The restored state replaces the start positions: no equilibrium solve.
            Simulation::new(crate::model::Model::new(&scene).map_err(|e| e.to_string())?)
        };
        sim.inputs.force_density = self.force_density.clone();
        sim.inputs.node_force = self.node_force.clone();
        sim.inputs.rest_length = self.rest_length.clone();
        sim.set_state(self.state.clone());
        sim.set_grips(&self.grips());
        sim.restore_carried(self.h_next, &self.carried);
        core.sim = sim;
        core.scene = scene;
        core.mode = self.mode;
        core.time = self.time;
        core.stop_time = self.stop_time;
        core.warned_negative = self.warned_negative.clone();
        core.rebuild = self.rebuild;
        core.stale = false;
        Ok(())
    }

    /// The serialized form.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::new();
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        put_bytes(&mut out, self.guid.as_bytes());
        out.push(mode_code(self.mode));
        put_f64s(&mut out, &[self.time, self.state.time]);
        out.push(u8::from(self.stop_time.is_some()));
        put_f64s(&mut out, &[self.stop_time.unwrap_or(0.0)]);
        put_len(&mut out, self.state.y.len());
        put_f64s(&mut out, &self.state.y);
        put_len(&mut out, self.force_density.len());
        put_f64s(&mut out, &self.force_density);
        put_len(&mut out, self.node_force.len());
        for f in &self.node_force {
            put_f64s(&mut out, f.as_slice());
        }
        put_len(&mut out, self.rest_length.len());
        put_f64s(&mut out, &self.rest_length);
        put_bytes(
            &mut out,
            &self
                .warned_negative
                .iter()
                .map(|&w| u8::from(w))
                .collect::<Vec<_>>(),
        );
        out.push(u8::from(self.rebuild));
        put_len(&mut out, self.parameters.len());
        put_f64s(&mut out, &self.parameters);
        put_f64s(&mut out, &[self.h_next]);
        put_len(&mut out, self.carried.len());
        put_f64s(&mut out, &self.carried);
        put_len(&mut out, self.grips.len());
        put_f64s(&mut out, &self.grips);
        let digest = Sha256::digest(&out);
        out.extend_from_slice(&digest);
        out
    }

    /// Parses a serialized state, checking magic, version, GUID, checksum, flags and that
    /// every number is finite; the checks against the model follow in
    /// [`super::Instance::deserialize_state`] and [`super::Instance::set_state`].
    pub fn from_bytes(guid: &str, bytes: &[u8]) -> Result<Self, String> {
        let body_len = bytes
            .len()
            .checked_sub(DIGEST_LEN)
            .ok_or("truncated serialized state")?;
        let (bytes, digest) = bytes.split_at(body_len);
        let mut r = Reader { bytes, at: 0 };
        if r.take(MAGIC.len())? != MAGIC {
            return Err("not a serialized tensegrity-fmu state (bad magic)".into());
        }
        let version = u32::from_le_bytes(r.take(4)?.try_into().expect("4 bytes"));
        if version != VERSION {
            return Err(format!(
                "serialized state version {version}, expected {VERSION}"
            ));
        }
        let found =
            String::from_utf8(r.bytes()?.to_vec()).map_err(|_| "corrupt GUID".to_string())?;
        if found != guid {
            return Err(format!(
                "the state belongs to another FMU (GUID {found}, expected {guid})"
            ));
        }
        let mode = mode_from(r.u8()?)?;
        let time = r.f64()?;
        let state_time = r.f64()?;
        let has_stop = r.flag("the stop-time flag")?;
        let stop = r.f64()?;
        if !has_stop && stop != 0.0 {
            return Err(format!(
                "corrupt state: stop time {stop} s while its flag says there is none (allowed: 0)"
            ));
        }
        let n = r.len()?;
        let y = r.f64s(n)?;
        let n = r.len()?;
        let force_density = r.f64s(n)?;
        let n = r.len()?;
        let node_force = (0..n)
            .map(|_| Ok(Vector3::new(r.f64()?, r.f64()?, r.f64()?)))
            .collect::<Result<Vec<_>, String>>()?;
        let n = r.len()?;
        let rest_length = r.f64s(n)?;
        let warned_negative = r
            .bytes()?
            .iter()
            .enumerate()
            .map(|(k, &b)| flag(b, &format!("negative-input warning flag {}", k + 1)))
            .collect::<Result<Vec<_>, String>>()?;
        let rebuild = r.flag("the pending-rebuild flag")?;
        let n = r.len()?;
        let parameters = r.f64s(n)?;
        let h_next = r.f64()?;
        let n = r.len()?;
        let carried = r.f64s(n)?;
        let n = r.len()?;
        let grips = r.f64s(n)?;
        if r.at != bytes.len() {
            return Err("trailing bytes after the serialized state".into());
        }
        if Sha256::digest(bytes).as_slice() != digest {
            return Err("corrupt serialized state (checksum mismatch)".into());
        }
        let forces: Vec<f64> = node_force.iter().flat_map(|f| f.iter().copied()).collect();
        let fields: [(&str, &[f64]); 11] = [
            ("time", &[time]),
            ("the integrated state's time", &[state_time]),
            ("stop time", &[stop]),
            ("state vector (η₂ and η̇₂)", &y),
            ("force-density inputs", &force_density),
            ("node-force inputs", &forces),
            ("rest-length inputs", &rest_length),
            ("parameter values", &parameters),
            ("the adaptive method's next step", &[h_next]),
            ("values carried by the integrator", &carried),
            ("friction grips", &grips),
        ];
        for (what, values) in fields {
            if let Some(k) = values.iter().position(|x| !x.is_finite()) {
                return Err(format!(
                    "corrupt state: {what}: value {} is {}, not a finite number",
                    k + 1,
                    values[k]
                ));
            }
        }
        if grips.len() % 4 != 0 {
            return Err(format!(
                "corrupt state: {} friction-grip values, not four per grip",
                grips.len()
            ));
        }
        for (k, v) in grips.as_chunks::<4>().0.iter().enumerate() {
            if Grip::from_values(*v).is_none() {
                return Err(format!(
                    "corrupt state: friction grip {} has mode {} (allowed: 0 free, 1 stick, \
                     2 slip)",
                    k + 1,
                    v[0]
                ));
            }
        }
        // The communication time and the integrated state's time always agree; an edited
        // one would send the next fmi2DoStep integrating across the gap.
        if time != state_time {
            return Err(format!(
                "inconsistent state: its communication time {time} s differs from the time of \
                 its integrated state {state_time} s (edited or corrupt); use a state saved by \
                 fmi2SerializeFMUstate unchanged"
            ));
        }
        Ok(Self {
            guid: found,
            mode,
            time,
            stop_time: has_stop.then_some(stop),
            state: State {
                time: state_time,
                y,
            },
            force_density,
            node_force,
            rest_length,
            warned_negative,
            rebuild,
            parameters,
            h_next,
            carried,
            grips,
        })
    }
}

fn parameter_variables(core: &Core) -> impl Iterator<Item = &Variable> + '_ {
    core.table
        .variables
        .iter()
        .filter(|v| v.causality == Causality::Parameter)
}

/// A Boolean byte: 0 or 1, nothing else.
fn flag(byte: u8, what: &str) -> Result<bool, String> {
    match byte {
        0 => Ok(false),
        1 => Ok(true),
        _ => Err(format!(
            "corrupt state: {what} is {byte}, but a Boolean is 0 or 1"
        )),
    }
}

fn mode_code(mode: Mode) -> u8 {
    match mode {
        Mode::Instantiated => 0,
        Mode::InitializationMode => 1,
        Mode::StepComplete => 2,
        Mode::Terminated => 3,
        Mode::Error => 4,
    }
}

fn mode_from(code: u8) -> Result<Mode, String> {
    Ok(match code {
        0 => Mode::Instantiated,
        1 => Mode::InitializationMode,
        2 => Mode::StepComplete,
        3 => Mode::Terminated,
        4 => Mode::Error,
        _ => return Err(format!("corrupt state: mode code {code}")),
    })
}

fn put_len(out: &mut Vec<u8>, n: usize) {
    out.extend_from_slice(&(n as u64).to_le_bytes());
}

fn put_bytes(out: &mut Vec<u8>, b: &[u8]) {
    put_len(out, b.len());
    out.extend_from_slice(b);
}

fn put_f64s(out: &mut Vec<u8>, xs: &[f64]) {
    for x in xs {
        out.extend_from_slice(&x.to_le_bytes());
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or("truncated serialized state")?;
        let slice = &self.bytes[self.at..end];
        self.at = end;
        Ok(slice)
    }
    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    fn flag(&mut self, what: &str) -> Result<bool, String> {
        flag(self.u8()?, what)
    }
    fn len(&mut self) -> Result<usize, String> {
        let n = u64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes"));
        usize::try_from(n).map_err(|_| "corrupt length".to_string())
    }
    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    fn f64s(&mut self, n: usize) -> Result<Vec<f64>, String> {
        let bytes = self.take(n.checked_mul(8).ok_or("corrupt length")?)?;
        Ok(bytes
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect())
    }
    fn bytes(&mut self) -> Result<&'a [u8], String> {
        let n = self.len()?;
        self.take(n)
    }
}
