//! Writes the synthetic 1920×1080 frames of the processing benches as canonical pass files
//! `shutter blur` reads, one folder per scenario, for `scripts/same_bits.sh` (which checks
//! that a change keeps every output's bits):
//!
//! ```text
//! cargo run --release --example bench_frames -- target/frames/bench
//! ```
//!
//! - `moving/`: reconstruct/stretch "every pixel moving" (colour, depth, velocity);
//! - `scatter_moving/`: scatter's default "moving" frame, 30 px with a 3 px bend (colour,
//!   depth, prev, next);
//! - `static/`: nothing moves (colour, depth, zero velocity, prev = next = p(0));
//! - `sparse/`: the 5 % square (velocity (24, 8); prev/next with the scatter bench's (0, 2)
//!   bend);
//! - `dof/`: the dof bench's frame (depths 1.5, 3, 6, ∞ m in blocks), plus scatter's moving
//!   prev/next so that dof followed by scatter has motion to blur, and `lens.args` (the
//!   bench's lens as `shutter dof` flags).
//!
//! Written the way `shutter scene` writes its passes: f32, ZIP, R,G,B,A / Z / X,Y.

#[path = "../benches/common/mod.rs"]
mod common;

use std::path::Path;

use common::{H, W};
use shutter::frame::Frame;
use shutter::io::output::write_passes;

/// Writes every pass `f` holds into `dir` as `ROLE.0001.exr`.
fn write_frame(dir: &Path, f: Frame) {
    std::fs::create_dir_all(dir).expect("create the folder");
    write_passes(f, |role| dir.join(format!("{role}.0001.exr"))).unwrap_or_else(|p| panic!("{p}"));
    println!("{}", dir.display());
}

/// The velocity frame with the scatter frame's prev/next of the same scenario added (colour
/// and depth are the same in both generators).
fn both(
    velocity: impl Fn(usize, usize) -> Option<(f32, f32)>,
    positions: impl Fn(usize, usize) -> Option<([f32; 2], [f32; 2])>,
) -> Frame {
    let mut f = common::frame(velocity);
    let s = common::positions_frame(positions);
    assert!(f.color == s.color && f.depth == s.depth);
    f.prev = s.prev;
    f.next = s.next;
    f
}

fn main() {
    let root = std::env::args()
        .nth(1)
        .expect("usage: bench_frames OUTPUT_DIR");
    let root = Path::new(&root);

    // reconstruct.rs / stretch.rs: every pixel moving.
    write_frame(&root.join("moving"), common::frame(common::rotating));

    // scatter.rs: every pixel moving 30 px on a gently curved path.
    write_frame(
        &root.join("scatter_moving"),
        common::positions_frame(common::curving),
    );

    // static (all three benches).
    write_frame(&root.join("static"), both(|_, _| None, |_, _| None));

    // sparse: the 5 % square (the benches also time 1 % and 25 %).
    let side = ((W * H) as f32 * 0.05).sqrt() as usize;
    write_frame(
        &root.join("sparse"),
        both(
            |x, y| (x < side && y < side).then_some((24.0, 8.0)),
            |x, y| (x < side && y < side).then_some(([24.0, 8.0], [0.0, 2.0])),
        ),
    );

    // dof.rs: blocks at 1.5 m, 3 m (in focus), 6 m and infinity; lens 50 mm f/1.4 at 3 m.
    let mut f = common::lens_frame();
    let s = common::positions_frame(common::curving);
    f.prev = s.prev;
    f.next = s.next;
    write_frame(&root.join("dof"), f);
    // The dof bench's lens and max CoC, as `shutter dof` flags, for scripts/same_bits.sh.
    std::fs::write(
        root.join("dof/lens.args"),
        "--focal-length 50 --f-stop 1.4 --focus-distance 3 --sensor-width 36 --max-coc 32\n",
    )
    .expect("write lens.args");
}
