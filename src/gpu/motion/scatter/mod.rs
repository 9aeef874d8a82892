//! Motion blur's `scatter` pass on the GPU (`scatter.wgsl`; the device side in `pass.rs`):
//! the twin of [`crate::motion::scatter::scatter`] (Guertin & Nowrouzezahrai's curve
//! scatter), every normalisation (paper, exposure), curve kind (Bézier, arc) and weight (box,
//! Gaussian), the flatness-adaptive segment counts and the shutter offset, stage for stage:
//!
//! 1. `reach`: per pixel, the CPU's motion test (`Scatter::motion`: the curve's extent over
//!    the exposure against [`STILL`]); moving pixels join a list through an atomic counter
//!    and count their curve into their 16×16 block (the CPU's `BLOCK`): the block's curves,
//!    the farthest they reach, and per channel the largest |colour|. `scales` gathers, for
//!    each tile (a block's square), the blocks that can reach it: the fixed point of the
//!    tile's sums (below). `prepare` turns the count into the size of the next dispatch
//!    (indirect), so a still frame or still pixels cost no curve work.
//! 2. `accumulate`: one invocation per moving pixel builds its path as `Scatter::path` does
//!    (segments, weights, depths, scaling to `max_curve`, the exposure share) and walks each
//!    segment with [`crate::motion::line`]'s coverage model (a column's exact length, split
//!    linearly between the two nearest pixel centres), depth-tested against the frame, into
//!    fixed-point sums, in the units of the tile each deposit lands in.
//! 3. `resolve`: per pixel, eq. 4 or the exposure normalisation, with `behind` (the search
//!    along the motion for a farther surface) where a pixel is not wholly covered.
//!
//! Bindings, in order: the [`ScatterConfig`] uniform (the CPU's own struct), colour, depth,
//! prev, next (the CPU's inputs, planes one after the other), then `state` (the host's words,
//! then the blocks'), the moving list (then the tiles' scales), the five sums, the output
//! colour and the fringe's entries.
//!
//! **The fringe** ([`crate::motion::scatter::fringe`]) is found on the CPU for both backends
//! (its matte is reconstruct's, which runs there too): the colour uploaded is its unmixed
//! one, and its entries (still pixel, moving partner, coverage) go to a binding of their own.
//! `reach_fringe` appends each entry to the moving list, marked by its top bit; `accumulate`
//! draws a marked entry as its partner's curve (the motion relative to the pixel's corner is
//! the same) from the entry's own pixel, its weights times the coverage, as the CPU does.
//!
//! **Light layers** (RGB colours beside the beauty, sharing its alpha: issue 29) are carried
//! through the same dispatches, as the CPU's [`stages_carrying`] carries them through the
//! same curves: [`Gpu::try_scatter_carrying`]. The curves are drawn once; each deposit adds
//! every layer channel's value at the curve's pixel, with the weight it gives the beauty,
//! into a 64-bit sum of the channel's own (one buffer, a plane of two words a pixel per
//! channel, bind group 1), and `resolve` finds each pixel's resolution once (which
//! normalisation, the weight sum, the pixels behind) and applies it to the beauty's channels
//! and every layer's. Each layer channel has its own colour bound and fixed-point scale in
//! each tile, found by `reach` and `scales` over the same curves, so a layer's sums are the
//! bits it gets alone in the beauty's place, and so is its output where the compiler evaluates the two alike
//! (tests/gpu_scatter.rs measures it). Up to [`MOST_LAYERS`] layers ride one run, and as many
//! as their sums fit one storage binding (24 bytes a pixel a layer: two at 1080p under
//! lavapipe's 128 MiB); more are split into runs as even as they can be, each run drawing the
//! curves again (and the beauty's sums with them: its output is the first run's). Where not
//! even one layer fits, or the device allows fewer than [`CARRYING_STORAGE_BUFFERS`] storage
//! buffers per stage, each layer runs through the stages alone in the beauty's place, as
//! before layers were carried. A run that fails on the device all the same (out of memory, a
//! driver refusing the carrying module) is tried again with half as many layers a run, down
//! to each layer alone; where that cannot run either the whole frame runs on the CPU. (The
//! budget is one binding; a device's total memory is not asked: 60 bytes a pixel a layer,
//! about 4 GB for eight layers at 4K.)
//!
//! **Why two modules, not a layer count in the config.** The stages call hooks
//! (`carried_layers`, `carried_magnitude`, `carry_pen`, `carry_deposit`, `carry_resolve`): alone.wgsl defines them empty, carrying.wgsl carries the layers, and the
//! same scatter.wgsl, fixed.wgsl and curve.wgsl go into both ([`SHADER`], [`SHADER_CARRYING`]). A layer count in the config, read by one module,
//! would leave a loop and its count's load at every deposit of the beauty alone, and the
//! layers' bindings in its pipeline layout, needing buffers bound with no layers; an override
//! constant would still leave the bindings statically used (WGSL has no conditional
//! compilation) and compile a pipeline per count. The beauty alone's module is instead what
//! it was, bindings, sums and all (the hooks inline to nothing), and the carrying module is
//! compiled the first time a frame brings layers. Where a run carries layers its count is a
//! word of `state`, beside the host's flags, and their channels' bounds and scales follow
//! the beauty's in each block's and tile's words.
//!
//! **Why a compute rasteriser with integer atomics, not the render pipeline's lines.** The
//! paper draws its segments as GL lines with additive blending into a float target. Measured
//! (docs/CRATES.md): lavapipe draws a 1-px line as a rectangle (coverage = Euclidean length) where
//! GL and many GPUs use the longer axis (~15 % less energy), so the same frame gives other
//! images on other drivers; and float blending adds in whatever order the hardware retires
//! fragments, so not even one driver repeats itself bit for bit. A compute rasteriser instead
//! runs our own coverage model — the CPU's, so the two can be compared at all — and
//! deposits into **64-bit fixed-point integer sums**: integer addition is associative, so the
//! result is the same for any dispatch order, workgroup size or thread count, bit for bit, by
//! construction (tests/gpu_scatter.rs checks two runs, two workgroup sizes and a reversed
//! list). WGSL has neither 64-bit integers nor 64-bit atomics, so each sum is two
//! `atomic<u32>` words: `atomicAdd` on the low word returns the old value, and where the
//! addition wrapped the high word takes the carry (with the high part); in two's complement,
//! so negative colours add too, and the sum modulo 2⁶⁴ does not depend on order. Float
//! atomics (`SHADER_FLOAT32_ATOMIC`) would be order-dependent; a sort of deposits by pixel
//! would be deterministic but costs a global sort per frame.
//!
//! **The fixed point** (fixed.wgsl). A sum is a 64-bit two's-complement integer counting
//! units of its tile (a 16×16 block's square) and colour (the beauty's R, G and B share one;
//! its alpha has its own; each carried layer's R, G and B share one): 2^(e − G), where 2^e is
//! the power of two above the largest |value| of any curve that can deposit in the tile (so
//! value · 2^−e lies in (−1, 1), exactly), and G, the fractional bits, is
//! min(62 − ⌈log₂ N⌉ − w, 32 + e − l): N the curves that can deposit in the tile, 2^w a bound
//! on the weight one curve deposits in one pixel (w = 7 for the paper's weights: at most 64
//! segments, each at most one deposit a pixel, of coverage ≤ √2 times a weight ≤ 1, so
//! 64·√2 ≈ 90.5 < 2⁷; w = 1 under the exposure normalisation, where a curve's deposits sum
//! to its coverage of the exposure, ≤ 1 < 2¹, the f32 rounding of that sum far inside the
//! factor 2), and 2^l the least typical magnitude (a block's mean exponent) among the
//! blocks whose curves can land there. Where the values landing are of one magnitude, G is
//! 32, the fixed point one frame-wide scale had, and a typical deposit fits the low word;
//! where a firefly lands among ordinary values, G grows by as many bits as it is brighter
//! than they are, so they keep their precision beside it. The weight's unit is the frame's,
//! 2^−min(32, 62 − ⌈log₂ N_frame⌉ − w) (weights are bounded where colours are not).
//!
//! Which curves can deposit in a tile: `reach` counts each into its block with a reach (a
//! whole number of pixels, along each axis, from the pixel it is drawn from): the Bézier's
//! extent plus the pixel beside it (the CPU's `Scatter::motion` bound, which the scaling to
//! `max_curve` only shrinks), and where that is farther than the longest curve or the curve
//! may be an arc, the farthest point of its path as `accumulate` builds it (an arc turning
//! past the far side of its circle, or a curve cut short far from p(0), strays beyond the
//! extent or the longest curve). `scales` adds up the blocks whose reach touches the tile,
//! and the rare curve that reaches farther than the longest curve can is counted into every
//! tile (FAR). The reach is kept beside the curve in the moving list and `accumulate` clips
//! every walk to it, so no deposit lands in a tile that did not count its curve — by
//! construction, not by trusting the geometry or two stages' roundings to agree.
//!
//! *No overflow, by construction.* At a pixel of the tile, in channel c of a colour: each
//! deposit is (d · 2^(G − e)) · value, with |value · 2^−e| < 1, and the deposits of one
//! curve there add up to at most 2^w in d, so the exact deposits sum to
//! |Σ| < N · 2^w · 2^G ≤ 2^(⌈log₂ N⌉ + w + 62 − ⌈log₂ N⌉ − w) = 2⁶²; rounding each deposit
//! to a unit adds at most ½, and a curve makes at most 64 deposits a pixel (one a segment),
//! so at most 32·N < 2³⁶ more (N < 2³¹: a curve a moving pixel or fringe entry), and the f32
//! product's own rounding (2⁻²⁴ of it) a further 2³⁸ at most. |Σ| < 2⁶² + 2⁴⁰ < 2⁶³: the
//! sum never wraps, whatever the values (the numeric policy's 10³⁰ included). No f32 along
//! the way is out of range: G lies in 24..=61, e is taken no lower than G − 125 (a value
//! below 2^(G − 125) ≤ 2⁻⁶⁴ is below a unit anyway), so 2^(G − e) is a normal float and
//! d · 2^(G − e) ≤ 2 · 2¹²⁵; the weight is scaled by 2^G alone. Decoding converts the
//! magnitude (a negative sum negated first) in three f32 roundings and scales it back by a
//! power of two; resolve computes in the tile's scaled units (a weighted mean of values below
//! 2^e stays below it) and scales back at the end, the paper's eq. 4 adding the pixel's own
//! colour unscaled (a still pixel, which 2^e need not bound), so the output is finite.
//!
//! *The error, bounded locally.* A deposit is rounded to half a unit, 2^(e − G − 1): a
//! fraction 2^−(G+1) of the largest value that can land in its tile, where the frame's
//! largest used to set it for every pixel. One firefly of 10⁷ (2²⁴) therefore changes only
//! the tiles its own curve can reach, and there its deposits get 24 more fractional bits, up
//! to 62 − ⌈log₂ N⌉ − w (49 for an ordinary frame's few thousand curves a tile under the
//! exposure normalisation): 2^(24 − 49) ≈ 3·10⁻⁸ of a unit colour for the ordinary deposits
//! beside it (tests/gpu_scatter.rs's firefly tests measure it against the CPU, on the streak
//! and off it). A firefly 2^b brighter than its neighbours leaves them 62 − ⌈log₂ N⌉ − w − b
//! fractional bits of their own magnitude (25 beside 10⁷). Beyond 2²⁴ that would run out
//! (beside 10³⁰, none: every ordinary pixel in its reach black), so a frame with any colour
//! beyond 2²⁴ is split into bands of 2²⁴ ([`bands`]), each carried as a light layer with
//! fixed points of its own and added back: an ordinary pixel's sums are then band 0's,
//! whatever lies in reach.
//!
//! *The cost.* A deposit reads its tile's factor (one word, the beauty's colour and alpha
//! bytes) and scales its weight by it; `reach` counts each curve into its block, building
//! its path only for arcs and curves longer than `max_curve`; `scales` runs once per tile.
//! Measured on lavapipe at 960×540 (the 540p test), about a fifth more time than one
//! frame-wide scale (which per-deposit lookup of any kind pays on a CPU driver, where every
//! lane runs every branch).
//!
//! **The f32 form.** WGSL has no f64, and the CPU's geometry is absolute f64 (positions may
//! lie 10¹² px off-screen). Here every position is taken relative to the corner of the
//! moving pixel (p(0) = (½, ½), pixel boundaries at integers), so after the scaling to
//! `max_curve` every point of a curve lies within `max_curve` px of the origin and f32 holds
//! it to ~2⁻¹⁵ px; far positions lose only their own relative rounding (6·10⁻⁸), which the
//! scaling shrinks with them. The arc's points are formed in chord form about p(0) (see
//! `arc_at` in the shader) because the CPU's centre + r·(cos, sin) cancels digits of the
//! radius (up to 10⁷ px), and its turns from p(0) to p(±1) are taken at once (atan2 of the
//! cross and dot products of the two radii) rather than as differences of absolute angles
//! (measured: the arcs' largest difference from the CPU fell from 1.8·10⁻⁴ to 3·10⁻⁵ of the
//! range). The CPU keeps its f64: the two agree to f32 rounding of the
//! geometry, which moves a coverage by ~10⁻⁵ of a pixel; where a rounding moves a decision (a
//! segment count at a flatness boundary, a depth test on its threshold, the still test at
//! exactly [`STILL`]) a pixel differs by more, rarely; tests/gpu_scatter.rs states and
//! measures both. (Making the CPU follow the f32 form would change nothing it measures and
//! give up what f64 buys it: sums that repeat a colour exactly.)
//!
//! Other differences from the CPU, none visible in output: the CPU visits curves tile by tile
//! and keeps f64 sums; the GPU visits each curve once (the sums make order immaterial). A
//! segment whose depth is not finite at either end draws nothing, as on the CPU (where its
//! depth change is NaN and fails every test). The CPU's block-deepest shortcut in `behind`
//! only skips searches that find nothing and is dropped.
//!
//! A frame larger than one storage binding (its colour, 16 bytes a pixel: 128 MiB on
//! lavapipe, a 4K frame), or a device with fewer than [`STORAGE_BUFFERS`] storage buffers per
//! stage, runs on the CPU, counted and warned about, as every twin does.

mod bands;
mod pass;

use crate::frame::{Color, Positions};
use crate::motion::scatter::ScatterConfig;

#[cfg(doc)]
use crate::motion::scatter::{stages_carrying, STILL};

use crate::gpu::context::Gpu;
use crate::gpu::stage::StageError;
use crate::motion::scatter::Fringe;
use pass::{carried_sum_bytes, Inputs};
pub use pass::{
    Order, CARRYING_STORAGE_BUFFERS, MOST_LAYERS, SHADER, SHADER_CARRYING, STORAGE_BUFFERS,
};

impl Gpu {
    /// Scatter's three stages on the GPU ([`crate::motion::scatter::stages`]' arguments and
    /// result), dispatched in `order` (a test hook: the output must not depend on it), or why
    /// they could not run.
    pub fn try_scatter(
        &self,
        config: &ScatterConfig,
        color: &Color,
        depth: &[f32],
        positions: [&Positions; 2],
        fringe: &Fringe,
        order: Order,
    ) -> Result<Color, StageError> {
        if config.width == 0 || config.height == 0 {
            return Ok(color.clone());
        }
        if let Some(split) = bands::split(color, &[]) {
            return self.scatter_banded(config, split, (depth, positions, fringe), &mut [], order);
        }
        let inputs = (depth, positions, fringe);
        let (beauty, _) = self.run_scatter(config, color, inputs, order, &[])?;
        Ok(beauty)
    }

    /// A frame whose colours lie beyond band 0 ([`bands`]): band 0 of the beauty and of
    /// `layers` in their places, the bands above carried beside them, the outputs added back.
    fn scatter_banded(
        &self,
        config: &ScatterConfig,
        mut split: bands::Split,
        (depth, positions, fringe): Inputs,
        layers: &mut [Color],
        order: Order,
    ) -> Result<Color, StageError> {
        let mut outputs = std::mem::take(&mut split.layers);
        let beauty = self.carrying(
            config,
            &split.beauty,
            (depth, positions, fringe),
            &mut outputs,
            order,
        )?;
        Ok(split.join(beauty, outputs, layers))
    }

    /// [`crate::motion::scatter::stages_carrying`] on the GPU: the beauty's output, and the
    /// R, G and B of `layers` (light layers, whose alpha is the beauty's) blurred in place
    /// with the beauty's weights, carried through the same dispatches in runs of at most
    /// [`Gpu::scatter_layers_per_run`] (each layer alone in the beauty's place where that is
    /// 0); or why they could not run, the layers then untouched.
    #[allow(clippy::too_many_arguments)]
    pub fn try_scatter_carrying(
        &self,
        config: &ScatterConfig,
        color: &Color,
        depth: &[f32],
        positions: [&Positions; 2],
        fringe: &Fringe,
        layers: &mut [Color],
        order: Order,
    ) -> Result<Color, StageError> {
        let pixels = config.width as usize * config.height as usize;
        if pixels == 0 || layers.is_empty() {
            return self.try_scatter(config, color, depth, positions, fringe, order);
        }
        let inputs = (depth, positions, fringe);
        if let Some(split) = bands::split(color, layers) {
            return self.scatter_banded(config, split, inputs, layers, order);
        }
        self.carrying(config, color, inputs, layers, order)
    }

    /// [`Gpu::try_scatter_carrying`] of colours within band 0, `layers` not empty.
    fn carrying(
        &self,
        config: &ScatterConfig,
        color: &Color,
        inputs: Inputs,
        layers: &mut [Color],
        order: Order,
    ) -> Result<Color, StageError> {
        let pixels = config.width as usize * config.height as usize;
        // A run that fails on the device (out of memory, a driver refusing the carrying
        // module) is tried again with half as many layers a run, down to each layer alone in
        // the beauty's place, before the frame goes to the CPU.
        let mut per_run = self.scatter_layers_per_run(pixels, order);
        let (beauty, planes) = loop {
            match self.scatter_runs(config, color, inputs, layers, order, per_run) {
                Ok(done) => break done,
                Err(why) if per_run == 0 || !order.retry => return Err(why),
                Err(_) => per_run /= 2,
            }
        };
        let mut planes = planes.into_iter();
        for layer in layers.iter_mut() {
            for plane in [&mut layer.r, &mut layer.g, &mut layer.b] {
                *plane = planes.next().expect("three planes a layer");
            }
        }
        Ok(beauty)
    }

    /// The beauty's output and every layer's R, G and B planes through runs of at most
    /// `per_run` layers (each layer alone in the beauty's place where that is 0), kept until
    /// every run has run: a failure leaves the layers as they came.
    fn scatter_runs(
        &self,
        config: &ScatterConfig,
        color: &Color,
        inputs: Inputs,
        layers: &[Color],
        order: Order,
        per_run: usize,
    ) -> Result<(Color, Vec<Vec<f32>>), StageError> {
        let mut planes = Vec::with_capacity(3 * layers.len());
        if per_run == 0 {
            for layer in layers {
                let (out, _) = self.run_scatter(config, layer, inputs, order, &[])?;
                planes.extend([out.r, out.g, out.b]);
            }
            let (beauty, _) = self.run_scatter(config, color, inputs, order, &[])?;
            return Ok((beauty, planes));
        }
        // Runs as even as they can be (as many as the most a run carries needs): the buffers
        // made for the first serve every one.
        let runs = layers.len().div_ceil(per_run);
        let size = layers.len().div_ceil(runs);
        let mut beauty = None;
        for run in layers.chunks(size) {
            let run: Vec<&Color> = run.iter().collect();
            let (out, carried) = self.run_scatter(config, color, inputs, order, &run)?;
            beauty.get_or_insert(out);
            planes.extend(carried);
        }
        Ok((beauty.expect("a run of the beauty"), planes))
    }

    /// The most light layers one run of [`Gpu::try_scatter_carrying`] carries over `pixels`:
    /// at most `order.layers` and [`MOST_LAYERS`], as many as their sums fit one storage
    /// binding, and 0 (each in the beauty's place) on a device with fewer storage buffers per
    /// stage than [`CARRYING_STORAGE_BUFFERS`].
    pub fn scatter_layers_per_run(&self, pixels: usize, order: Order) -> usize {
        let allowed = self.device.limits().max_storage_buffers_per_shader_stage;
        if allowed < CARRYING_STORAGE_BUFFERS {
            return 0;
        }
        let fit = (self.max_binding() / carried_sum_bytes(pixels.max(1), 1)) as usize;
        fit.min(MOST_LAYERS).min(order.layers)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::scatter as cpu;

    /// The hooks' empty definitions, last in [`SHADER`].
    const ALONE: &str = include_str!("alone.wgsl");

    #[test]
    fn the_config_is_the_cpu_s_thirteen_words_in_both_languages() {
        // Keep in sync with scatter.wgsl: thirteen 4-byte fields, no padding (both modules
        // take it from there).
        assert_eq!(std::mem::size_of::<ScatterConfig>(), 52);
        assert_eq!(std::mem::align_of::<ScatterConfig>(), 4);
        for shader in [SHADER, SHADER_CARRYING] {
            crate::gpu::layout::assert_same_layout!(
                ScatterConfig,
                shader,
                "ScatterConfig",
                [
                    width,
                    height,
                    shutter,
                    offset,
                    segments,
                    sigma,
                    gaussian,
                    background_weight,
                    exposure,
                    arc,
                    max_curve,
                    flatness,
                    depth_tolerance
                ]
            );
        }
    }

    #[test]
    fn the_shader_s_constants_are_the_cpu_s() {
        use super::pass::{
            BLOCK, BLOCKS, BLOCK_WORDS, COLOURS, DISPATCH, FLAGS, FRINGES, HAS_Z, LAYERS,
            MOST_GROUPS, MOST_REACH, OPAQUE, TILE_WORDS,
        };
        // scatter.wgsl and curve.wgsl go into both modules alike.
        assert!(SHADER_CARRYING.starts_with(SHADER.trim_end_matches(ALONE)));
        let has = |line: String| assert!(SHADER.contains(&line), "scatter.wgsl lacks {line}");
        has(format!("const STILL: f32 = {:?};", cpu::STILL as f32));
        has(format!(
            "const MOST_SEGMENTS: u32 = {}u;",
            cpu::MOST_SEGMENTS
        ));
        has(format!(
            "const COVERED: f32 = {:?};",
            cpu::config::COVERED as f32
        ));
        has(format!(
            "const COLLINEAR: f32 = {:?};",
            crate::motion::curve::COLLINEAR as f32
        ));
        has(format!(
            "const LARGEST_RADIUS: f32 = {:?};",
            crate::motion::curve::LARGEST_RADIUS as f32
        ));
        has(format!("const TAU: f32 = {:?};", std::f32::consts::TAU));
        has(format!("const PI: f32 = {:?};", std::f32::consts::PI));
        has(format!("const FLAGS: u32 = {FLAGS}u;"));
        has(format!("const DISPATCH: u32 = {DISPATCH}u;"));
        has(format!("const OPAQUE: u32 = {OPAQUE}u;"));
        has(format!("const HAS_Z: u32 = {HAS_Z}u;"));
        has(format!("const MOST_GROUPS: u32 = {MOST_GROUPS}u;"));
        has(format!("const LAYERS: u32 = {LAYERS}u;"));
        has(format!("const MOST_REACH: u32 = {MOST_REACH}u;"));
        has(format!("const BLOCKS: u32 = {BLOCKS}u;"));
        has(format!("const COLOURS: u32 = {COLOURS}u;"));
        has(format!("const BLOCK_WORDS: u32 = {BLOCK_WORDS}u;"));
        has(format!("const TILE_WORDS: u32 = {TILE_WORDS}u;"));
        // The tiles are the CPU's blocks.
        assert_eq!(BLOCK as usize, cpu::config::BLOCK);
        has(format!("const BLOCK: u32 = {BLOCK}u;"));
        has(format!("const FRINGES: u32 = {FRINGES}u;"));
        has(format!(
            "@binding({}) var<storage, read_write> out",
            STORAGE_BUFFERS - 1
        ));
        has(format!(
            "@binding({STORAGE_BUFFERS}) var<storage, read_write> fringe"
        ));
        // The carrying module: its bindings, and as many layers as the host gives a run.
        let carries = |line: String| {
            assert!(
                SHADER_CARRYING.contains(&line),
                "carrying.wgsl lacks {line}"
            )
        };
        carries(format!("const MOST_LAYERS: u32 = {MOST_LAYERS}u;"));
        carries(format!("const MOST_CARRIED: u32 = {}u;", 3 * MOST_LAYERS));
        let groups = CARRYING_STORAGE_BUFFERS - STORAGE_BUFFERS;
        carries(format!(
            "@group(1) @binding({}) var<storage, read_write> carried_out",
            groups - 1
        ));
        assert!(
            !SHADER.contains("@group(1)"),
            "the beauty alone binds no layers"
        );
        // The private path arrays hold the most segments.
        has(format!(
            "var<private> lengths: array<f32, {}>;",
            cpu::MOST_SEGMENTS
        ));
        has(format!(
            "var<private> points: array<vec2<f32>, {}>;",
            cpu::MOST_SEGMENTS + 1
        ));
    }
}
