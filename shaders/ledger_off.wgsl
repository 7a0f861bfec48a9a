// ledger_off.wgsl — the step without the energy ledger and contact statistics: the hooks
// of ledger.wgsl as no-ops; the state then has no ledger fields (`gpu::state`), so none is
// allocated.

const LEDGER: bool = false;

struct LedgerAcc {
    unused: f32,
}

fn ledger_new() -> LedgerAcc {
    return LedgerAcc(0.0);
}

fn ledger_pair(acc: ptr<function, LedgerAcc>, old: vec4<f32>, k: Kin, c: Contact, power: f32, is_in: bool, edges: vec4<f32>, touch: f32) {}

fn ledger_wall(acc: ptr<function, LedgerAcc>, old: vec4<f32>, k: Kin, c: Contact, power: f32, is_in: bool, edges: vec4<f32>, touch: f32, v_n: f32, jump: f32, drag: f32) {}

fn ledger_departed(acc: ptr<function, LedgerAcc>, old: vec4<f32>, delta: f32) {}

fn ledger_store(k: u32, acc: LedgerAcc) {}

fn ledger_dropped(old_row: u32, old_n: u32, k: u32) {}
