//! `stack_probe <op> <iterations>`: calls `cw_firmware::stack_probe::probe_<op>` that
//! many times, for callgrind (`cargo xtask callgrind` collects inside the probe only). The
//! probes and what each does: `cw_firmware::stack_probe`.

use cw_firmware::stack_probe::{Probe, Stack};

fn main() -> Result<(), String> {
    let mut args = std::env::args().skip(1);
    let usage = "usage: stack_probe <op> <iterations>";
    let op = args.next().ok_or(usage)?;
    let n: u32 = args.next().and_then(|s| s.parse().ok()).ok_or(usage)?;
    let probe = Probe::named(&op).ok_or_else(|| format!("unknown op {op}"))?;
    let mut s = Stack::started()?;
    let mut sink = 0u64;
    for i in 0..n {
        sink ^= s.call(probe, i, |_| ());
    }
    println!(
        "{op} x{n}: sink {sink} mailbox {:?}",
        s.can.frame.map(|f| f.len())
    );
    Ok(())
}
