//! `library-user`: a scenario written and run with the scenario language
//! alone, on the emulator, as a program of a team's own would do it
//! (`cargo run -p library-user`).

use ppmc::backend::EmuTarget;
use ppmc::runner::run_suite;
use ppmc::scenario::prelude::*;
use std::process::ExitCode;

/// a constant-speed move of 100 CW steps at rate 100 gives 100 pulses and
/// finishes normally
#[scenario(section = "3-3-5", tags("example"))]
fn a_constant_move_of_100_steps(d: &mut Driver) -> Outcome {
    d.init_and_wait(Init::four_phase())?;
    d.run(Move::constant(Cw, 100, 100))?;
    d.expect_pulses(100, Cw)?;
    d.expect_remaining(0)
}

fn main() -> ExitCode {
    let suite = vec![a_constant_move_of_100_steps()];
    let mut target = match EmuTarget::new(Default::default(), Default::default()) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("library-user: {e}");
            return ExitCode::from(2);
        }
    };
    let results = run_suite(&mut target, &suite, 1, Default::default(), |_| {});
    for r in &results {
        println!("{} {}", r.name, r.verdict.label());
    }
    match results.iter().all(|r| r.verdict.ok()) {
        true => ExitCode::SUCCESS,
        false => ExitCode::FAILURE,
    }
}
