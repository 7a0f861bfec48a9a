// jump_off.wgsl — the step without force jumps placed (the scene's `jump_impulses =
// false`): the hooks of jump.wgsl as no-ops, so no kernel touches what they need.

const JUMPS: bool = false;

fn contact_jump(old: vec4<f32>, k: Kin, c: Contact, is_in: bool, edges: vec4<f32>, touch: f32) -> f32 {
    return 0.0;
}

fn jump_kick(k: u32, dv: vec3<f32>) {}

