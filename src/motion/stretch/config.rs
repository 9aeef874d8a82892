//! stretch's parameters and its config, the uniform its GPU twin uploads, with the numeric
//! constants its stages share.

use crate::motion::shutter::Shutter;

/// A pixel whose streak over the exposure is shorter than this many pixels is still.
pub const STILL: f32 = 0.5;
/// At most this many samples along a pixel's motion in the texture pre-blur.
pub const MOST_SAMPLES: usize = 64;
/// A vertex moves at most this many pixels over the exposure (its move is cut to this
/// length, direction kept), as reconstruct's blur radius k is 128 px by default. A triangle's
/// cost grows with its moved vertex's distance, and velocities up to the numeric policy's
/// 1e7 px would otherwise make sliver triangles across the whole frame: with 10% of pixels
/// at 1e9 px and 30% at depth 0 (tearing the mesh everywhere), 640×360 took 1.2 s against
/// 0.2 s without those velocities and 1280×720 12.6 s against 0.75 s, growing with the
/// square of the pixel count (issue 17). By then such a smear is at the alpha floor.
pub const MAX_SHIFT: f32 = 128.0;

/// Where the sharp object sits within its streak.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Anchor {
    /// At the end of the exposure (the talk's rear-curtain form): trailing vertices move
    /// back by the whole exposure.
    Rear,
    /// In the middle (our shutter is centred on the frame): trailing vertices back, leading
    /// ones forward, by half the exposure each.
    Centre,
}

impl Anchor {
    /// Every choice, by the name flags and presets use.
    pub const ALL: &'static [(&'static str, Anchor)] =
        &[("centre", Anchor::Centre), ("rear", Anchor::Rear)];
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StretchParams {
    /// `extent` of `alpha = max(min_alpha, 1 − |M|/extent)`, pixels. Default 2, chosen on the
    /// bench: larger extents leave the smears too opaque (BENCHMARKS.md).
    pub extent: f32,
    /// The alpha floor (the talk's 0.1).
    pub min_alpha: f32,
    /// Relative depth step that tears the mesh.
    pub tear: f32,
    pub anchor: Anchor,
    /// Average each moving pixel's colour along its own motion first.
    pub texture_blur: bool,
    /// A fragment is drawn over a pixel whose depth is at least its own / (1 + this).
    pub depth_tolerance: f32,
}

impl Default for StretchParams {
    fn default() -> Self {
        StretchParams {
            extent: 2.0,
            min_alpha: 0.1,
            tear: 0.05,
            anchor: Anchor::Centre,
            texture_blur: true,
            depth_tolerance: 0.02,
        }
    }
}

/// Everything stretch's stages read besides their buffers, as plain numbers: the uniform of
/// its GPU twin (keep in sync with `struct StretchConfig` in src/gpu/motion/stretch.wgsl; a test
/// there compares the fields).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "gpu", derive(bytemuck::Pod, bytemuck::Zeroable))]
#[repr(C)]
pub struct StretchConfig {
    /// Frame size, pixels.
    pub width: u32,
    pub height: u32,
    /// Fraction of the frame interval the shutter is open.
    pub shutter: f32,
    /// The exposure, in frames relative to the frame's own time: [t0, t1].
    pub t0: f32,
    pub t1: f32,
    /// 1 + the tear ratio: neighbours whose depths differ by more are not joined.
    pub tear: f32,
    /// `extent` of a moved vertex's alpha, pixels (at least 1e-6).
    pub extent: f32,
    /// The alpha floor, in [0, 1].
    pub min_alpha: f32,
    /// 1 + the depth tolerance: a fragment is drawn where its depth ≤ the pixel's × this.
    pub depth_limit: f32,
    /// 1 where colour is averaged along the motion first ([`texture_blur`](super::texture_blur)), else 0.
    pub texture_blur: u32,
    /// 0, always: the GPU twin's products that must round as the CPU's do read it (an OR with
    /// a word no shader compiler can know is 0 keeps a driver from fusing a product into an
    /// add: `apart` in src/gpu/prelude.wgsl). The CPU never reads it.
    pub zero: u32,
    /// Padding to a whole 16 bytes (a uniform's size on every backend).
    pub _pad: u32,
}

impl StretchConfig {
    /// Whether colour is averaged along the motion first, typed (the GPU reads the word).
    pub fn texture_blur(&self) -> bool {
        self.texture_blur != 0
    }

    pub fn new(
        width: usize,
        height: usize,
        params: &StretchParams,
        shutter: impl Into<Shutter>,
    ) -> Self {
        let shutter = shutter.into();
        // Rear is the talk's rear curtain: the frame closes the exposure whatever the offset
        // (it is the centre anchor of `--shutter-offset end`). Centre follows the exposure
        // wherever the offset puts it.
        let (t0, t1) = match params.anchor {
            Anchor::Rear => (-shutter.open, 0.0),
            Anchor::Centre => shutter.interval(),
        };
        let shutter = shutter.open;
        StretchConfig {
            width: width as u32,
            height: height as u32,
            shutter,
            t0,
            t1,
            tear: 1.0 + params.tear.max(0.0),
            extent: params.extent.max(1e-6),
            min_alpha: params.min_alpha.clamp(0.0, 1.0),
            depth_limit: 1.0 + params.depth_tolerance.max(0.0),
            texture_blur: params.texture_blur as u32,
            zero: 0,
            _pad: 0,
        }
    }

    /// Whether a pixel of velocity `v` streaks far enough over the exposure to move.
    #[inline]
    pub fn moving(&self, [x, y]: [f32; 2]) -> bool {
        (x * x + y * y).sqrt() * self.shutter >= STILL
    }

    /// Whether two depths lie on different surfaces.
    #[inline]
    pub fn torn(&self, a: f32, b: f32) -> bool {
        a.max(b) > a.min(b) * self.tear
    }
}
