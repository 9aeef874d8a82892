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
use shutter::frame::{Frame, Windows};
use shutter::io::exr::ExrOptions;
use shutter::io::output::write_exr_atomic;

fn write(path: &Path, channels: Vec<(&str, Vec<f32>)>) {
    let channels = channels
        .into_iter()
        .map(|(n, p)| (n.to_string(), p))
        .collect();
    write_exr_atomic(
        path,
        W,
        H,
        Windows::full(W, H),
        channels,
        ExrOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

/// Writes every pass `f` holds into `dir` as `ROLE.0001.exr`.
fn write_frame(dir: &Path, f: Frame) {
    std::fs::create_dir_all(dir).expect("create the folder");
    let file = |role: &str| dir.join(format!("{role}.0001.exr"));
    if let Some(c) = f.color {
        let a = c.a.expect("alpha");
        write(
            &file("color"),
            vec![("R", c.r), ("G", c.g), ("B", c.b), ("A", a)],
        );
    }
    if let Some(z) = f.depth {
        write(&file("depth"), vec![("Z", z)]);
    }
    if let Some(v) = f.velocity {
        write(&file("velocity"), vec![("X", v.x), ("Y", v.y)]);
    }
    for (role, p) in [("prev", f.prev), ("next", f.next)] {
        if let Some(p) = p {
            let mut channels = vec![("X", p.x), ("Y", p.y)];
            if let Some(z) = p.z {
                channels.push(("Z", z));
            }
            write(&file(role), channels);
        }
    }
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
    let moving = |x: usize, y: usize| {
        let a = (x as f32 * 0.002) + (y as f32 * 0.003);
        let speed = 10.0 + 30.0 * ((x + y) % 97) as f32 / 96.0;
        Some((a.cos() * speed, a.sin() * speed))
    };
    write_frame(&root.join("moving"), common::frame(moving));

    // scatter.rs: every pixel moving 30 px on a gently curved path.
    let scatter_moving = |x: usize, y: usize| {
        let a = (x as f32 * 0.002) + (y as f32 * 0.003);
        let (c, s) = (a.cos(), a.sin());
        Some(([30.0 * c, 30.0 * s], [-3.0 * s, 3.0 * c]))
    };
    write_frame(
        &root.join("scatter_moving"),
        common::positions_frame(scatter_moving),
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
    let mut f = common::frame(|_, _| None);
    f.velocity = None;
    let depths = [1.5f32, 3.0, 6.0, f32::INFINITY];
    f.depth = Some(
        (0..W * H)
            .map(|i| depths[(i % W / 200 + i / W / 150) % 4])
            .collect(),
    );
    let s = common::positions_frame(scatter_moving);
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
