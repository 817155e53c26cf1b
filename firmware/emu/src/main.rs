mod machine;

use ppmc_bridge_fw::twin::chip::ChipSide;
use ppmc_core::emu::{Board as Model, ModelConfig};
use ppmc_core::protocol::Straps;

fn main() {
    let path = std::env::args().nth(1).expect("ELF");
    let cycles: u64 = std::env::args().nth(2).and_then(|s| s.parse().ok()).unwrap_or(30_000_000);
    let elf = std::fs::read(&path).expect("read");
    let flash = machine::flash_image(&elf).expect("flash");
    let model = Model::new(Straps::default(), ModelConfig::default()).expect("model");
    let chip = ChipSide::new(model, machine::SYS_CLK_HZ);
    let mut m = machine::Machine::boot(&flash, chip).expect("boot");
    let t0 = std::time::Instant::now();
    let step = 1_000_000;
    let mut done = 0;
    while done < cycles {
        m.run(step).expect("run");
        done += step;
        if done % 5_000_000 == 0 {
            println!(
                "{done}: core0 {:#x} core1 {:#x} launched {} writes {} reads {} floating {}",
                m.emu.core(0).regs.pc(),
                m.emu.core(1).regs.pc(),
                m.core1_launched(),
                m.chip().writes,
                m.chip().reads,
                m.floating
            );
        }
    }
    let s = t0.elapsed().as_secs_f64();
    println!("{:.1} M cycles/s", cycles as f64 / s / 1e6);
}
