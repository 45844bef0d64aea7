//! The scene fuzzer: generates inputs with proptest from a fixed seed, runs each through
//! [`pipeline::run`] under `catch_unwind`, times it, shrinks failures to a minimal input,
//! and counts what happened.
#![allow(dead_code)]

pub mod generate;
pub mod mutate;
pub mod pipeline;

use std::cell::{Cell, RefCell};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::sync::Once;
use std::time::{Duration, Instant};

use proptest::strategy::{Strategy, ValueTree};
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

use generate::Input;
use pipeline::Outcome;

/// CPU time past which an input counts as a hang.
pub const HANG: Duration = Duration::from_secs(1);
/// Failures of different kinds shrunk and kept for the report; others are only counted.
const KEPT_FAILURES: usize = 20;
/// Shrinking steps per failure.
const SHRINK_STEPS: u32 = 2000;

/// What a fuzz run saw.
#[derive(Debug, Default)]
pub struct Report {
    /// Inputs run.
    pub cases: u64,
    /// Inputs refused with a message.
    pub refused: u64,
    /// Inputs simulated.
    pub simulated: u64,
    /// Inputs that also took the FMU instance path.
    pub fmu: u64,
    /// Panics (also in `failures`).
    pub panics: u64,
    /// Broken properties other than panics.
    pub defects: u64,
    /// The first failure of each kind, shrunk: (input, what broke).
    pub failures: Vec<(Input, String)>,
    /// Inputs over [`HANG`] of CPU time, with their time.
    pub hangs: Vec<(Input, Duration)>,
    /// Total CPU time of the inputs.
    pub cpu: Duration,
    /// Largest CPU time of one input.
    pub cpu_max: Duration,
    /// Total wall time of the inputs.
    pub wall: Duration,
    /// Largest wall time of one input.
    pub wall_max: Duration,
}

impl Report {
    /// One paragraph for the log.
    pub fn summary(&self) -> String {
        let per = |d: Duration| d.as_secs_f64() * 1e6 / self.cases.max(1) as f64;
        format!(
            "{} inputs: {} refused with a message, {} simulated ({} also through the FMU \
             instance); {} panics, {} other defects, {} hangs (over {} s CPU); CPU time per \
             input mean {:.1} µs, max {:.1} ms; wall time per input mean {:.1} µs, max {:.1} ms",
            self.cases,
            self.refused,
            self.simulated,
            self.fmu,
            self.panics,
            self.defects,
            self.hangs.len(),
            HANG.as_secs(),
            per(self.cpu),
            self.cpu_max.as_secs_f64() * 1e3,
            per(self.wall),
            self.wall_max.as_secs_f64() * 1e3,
        )
    }
}

/// `FUZZ_CASES` or `default`, and `FUZZ_SEED` or 1.
pub fn settings(default_cases: u64) -> (u64, u64) {
    let var = |name: &str, default: u64| {
        std::env::var(name).map_or(default, |v| {
            v.parse()
                .unwrap_or_else(|_| panic!("{name} must be a whole number, got {v:?}"))
        })
    };
    (var("FUZZ_CASES", default_cases), var("FUZZ_SEED", 1))
}

thread_local! {
    /// The message of a panic inside [`check`], and whether [`check`] is running.
    static PANIC: RefCell<Option<String>> = const { RefCell::new(None) };
    static CHECKING: Cell<bool> = const { Cell::new(false) };
}

/// Keeps the messages of panics inside [`check`] for the report instead of printing them;
/// other panics (the test's own) print as usual.
fn quiet_panics() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let default = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if CHECKING.with(Cell::get) {
                PANIC.with(|p| *p.borrow_mut() = Some(panic_message(info)));
            } else {
                default(info);
            }
        }));
    });
}

fn panic_message(info: &std::panic::PanicHookInfo) -> String {
    let at = info
        .location()
        .map_or(String::new(), |l| format!(" at {}:{}", l.file(), l.line()));
    let message = info
        .payload()
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| info.payload().downcast_ref::<String>().cloned())
        .unwrap_or_default();
    format!("panic{at}: {message}")
}

/// This thread's CPU time.
fn cpu_time() -> Duration {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid timespec to write into.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    Duration::new(t.tv_sec as u64, t.tv_nsec as u32)
}

/// Runs one input: its outcome or what broke (a panic's message), with CPU and wall time.
pub fn check(input: &Input, dir: &Path) -> (Result<Outcome, String>, Duration, Duration) {
    quiet_panics();
    let (cpu, wall) = (cpu_time(), Instant::now());
    CHECKING.with(|c| c.set(true));
    let result = catch_unwind(AssertUnwindSafe(|| pipeline::run(input, dir)));
    CHECKING.with(|c| c.set(false));
    let result = result.unwrap_or_else(|_| {
        Err(PANIC
            .with(|p| p.borrow_mut().take())
            .unwrap_or_else(|| "panic".into()))
    });
    (result, cpu_time() - cpu, wall.elapsed())
}

/// Simplifies the failing input of `tree` while it keeps failing; returns the smallest
/// input and its failure.
fn shrink<T: ValueTree<Value = Input>>(tree: &mut T, dir: &Path, first: String) -> (Input, String) {
    let mut best = (tree.current(), first);
    let mut steps = 0;
    if !tree.simplify() {
        return best;
    }
    while steps < SHRINK_STEPS {
        steps += 1;
        let input = tree.current();
        let failed = match check(&input, dir).0 {
            Err(why) => {
                best = (input, why);
                tree.simplify()
            }
            Ok(_) => tree.complicate(),
        };
        if !failed {
            break;
        }
    }
    best
}

/// Runs `cases` inputs drawn alternately from `strategies` with the given seed.
pub fn fuzz<S: Strategy<Value = Input>>(strategies: &[S], cases: u64, seed: u64) -> Report {
    let dir = std::env::temp_dir().join(format!("tensegrity-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a scratch folder");
    let mut key = [0u8; 32];
    key[..8].copy_from_slice(&seed.to_le_bytes());
    let rng = TestRng::from_seed(RngAlgorithm::ChaCha, &key);
    let mut runner = TestRunner::new_with_rng(Config::default(), rng);
    let mut report = Report::default();
    let progress = (cases / 10).max(1);
    for case in 0..cases {
        let strategy = &strategies[case as usize % strategies.len()];
        let mut tree = strategy.new_tree(&mut runner).expect("a generated input");
        let input = tree.current();
        let (result, cpu, wall) = check(&input, &dir);
        report.cases += 1;
        report.cpu += cpu;
        report.wall += wall;
        report.cpu_max = report.cpu_max.max(cpu);
        report.wall_max = report.wall_max.max(wall);
        if cpu > HANG {
            report.hangs.push((input.clone(), cpu));
        }
        match result {
            Ok(Outcome::Refused) => report.refused += 1,
            Ok(Outcome::Simulated) => report.simulated += 1,
            Ok(Outcome::SimulatedFmu) => {
                report.simulated += 1;
                report.fmu += 1;
            }
            Err(why) => {
                if why.starts_with("panic") {
                    report.panics += 1;
                } else {
                    report.defects += 1;
                }
                let kind = signature(&why);
                if report.failures.len() < KEPT_FAILURES
                    && !report.failures.iter().any(|(_, w)| signature(w) == kind)
                {
                    let (input, why) = shrink(&mut tree, &dir, why);
                    if cases >= 100_000 {
                        eprintln!("{}", describe_one(&input, &why));
                    }
                    report.failures.push((input, why));
                }
            }
        }
        if cases >= 100_000 && (case + 1) % progress == 0 {
            eprintln!("{}", report.summary());
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    report
}

/// What kind of failure a message tells: its text without numbers, cut short.
fn signature(why: &str) -> String {
    why.chars()
        .filter(|c| !c.is_ascii_digit())
        .take(60)
        .collect()
}

/// The failures and hangs, each with its input, for the test's message.
pub fn describe(report: &Report) -> String {
    let mut text = String::new();
    for (input, why) in &report.failures {
        text += &describe_one(input, why);
    }
    for (input, time) in &report.hangs {
        text += &describe_one(input, &format!("hang: {:.2} s CPU", time.as_secs_f64()));
    }
    text
}

/// What broke, and the input.
fn describe_one(input: &Input, why: &str) -> String {
    let format = if input.json { "JSON" } else { "TOML" };
    format!("\n--- {why}\n{format} input:\n{}\n", input.text)
}
