
// ---- the beauty alone --------------------------------------------------------------------
//
// scatter.wgsl's hooks for light layers, empty: the module of the beauty alone carries none
// (carrying.wgsl is the module that does). Every compiler inlines them away, so this module
// is what scatter was before it carried layers, bindings and all.

fn carried_layers() -> u32 {
    return 0u;
}

fn carried_magnitude(l: u32, i: u32) -> f32 {
    return 0.0;
}

fn carry_pen(i: u32) {}

fn carry_deposit(p: u32, tile: u32, d: f32) {}

fn carry_resolve(p: u32, tile: u32, r: Resolution) {}
