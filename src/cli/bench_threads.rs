//! What the second thread buys: µs per rk4 step of large towers evaluated on one thread and
//! on two, measured in alternation in one process (this machine's speed drifts, so each
//! round's ratio is taken, and their median printed).

use tensegrity_fmu::{Model, Simulation};

use super::bench::{tower, us_per_step};

/// Prints, per tower height, µs per step on one thread and on two (the fastest round of
/// each) and the median of the rounds' ratios.
pub fn run(stages: &[usize], seconds: f64, rounds: usize) -> Result<(), String> {
    println!("| stages | bars | one thread (µs/step) | two threads (µs/step) | two / one |");
    println!("|---:|---:|---:|---:|---:|");
    for &k in stages {
        let model = Model::new(&tower(k)).map_err(|e| e.to_string())?;
        let bars = model.bars.len();
        let mut one = Simulation::new(model.clone());
        one.use_two_threads(false);
        let mut two = Simulation::new(model);
        two.use_two_threads(true);
        let (mut best, mut ratios) = ([f64::INFINITY; 2], Vec::new());
        for _ in 0..rounds.max(1) {
            let t = [
                us_per_step(&mut one, seconds)?,
                us_per_step(&mut two, seconds)?,
            ];
            best = [best[0].min(t[0]), best[1].min(t[1])];
            ratios.push(t[1] / t[0]);
        }
        ratios.sort_by(f64::total_cmp);
        let median = ratios[ratios.len() / 2];
        println!(
            "| {k} | {bars} | {:.0} | {:.0} | {median:.2} |",
            best[0], best[1]
        );
    }
    Ok(())
}
