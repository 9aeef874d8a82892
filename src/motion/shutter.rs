//! The exposure of a frame ([`Shutter`]): what every motion pass reads of the camera's
//! shutter, and what scatter's and stretch's configs and reconstruct's offset streaks are made
//! from.

/// The exposure of a frame: how long the shutter is open and where that interval sits about
/// the frame's own instant (docs/DESIGN.md, "Conventions").
///
/// With `open` = φ (the fraction of the frame interval the shutter is open) and `offset` = o,
/// the exposure covers the frame times t ∈ [(o − ½)·φ, (o + ½)·φ]: o is the middle of the
/// exposure, measured in exposures (fractions of φ), from the frame's instant. The named
/// offsets, as Nuke's `shutteroffset` and Blender's Cycles *Shutter Position* name them:
/// `centre` o = 0, [−φ/2, φ/2] (the default, and before issue 19 the only form); `start`
/// o = +½, [0, φ] (the shutter opens at the frame); `end` o = −½, [−φ, 0] (it closes at
/// the frame). Any o in [−½, ½] is allowed: the frame's instant then lies inside the
/// exposure, where the passes describe the image, and for φ ≤ 1 the exposure stays within
/// [−1, 1], the frames p(−1) and p(+1) span (so scatter's curves interpolate, never
/// extrapolate). Nuke's `custom` offset c (the time, in frames, at which the shutter opens)
/// is o = c/φ + ½.
///
/// A linearly moving point p(t) = p(0) + v·t smears over p(0) + v·[(o − ½)φ, (o + ½)φ]: the
/// centred streak ± v·φ/2 moved along its motion by v·o·φ, twice the offset in units of the
/// half-spread q = ½·v·φ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shutter {
    /// φ: fraction of the frame interval the shutter is open, in [0, 1].
    pub open: f32,
    /// o: the middle of the exposure after the frame's instant, in exposures, in [−½, ½].
    pub offset: f32,
}

impl Shutter {
    /// The named offsets, by the name flags and presets use.
    pub const OFFSETS: &'static [(&'static str, f32)] =
        &[("centre", 0.0), ("start", 0.5), ("end", -0.5)];

    /// A shutter open `open` of the frame, centred on it.
    pub const fn centred(open: f32) -> Shutter {
        Shutter { open, offset: 0.0 }
    }

    /// The exposure [t0, t1], frames relative to the frame's instant.
    #[inline]
    pub fn interval(self) -> (f32, f32) {
        (
            (self.offset - 0.5) * self.open,
            (self.offset + 0.5) * self.open,
        )
    }
}

impl From<f32> for Shutter {
    /// A centred shutter open `open` of the frame.
    fn from(open: f32) -> Shutter {
        Shutter::centred(open)
    }
}
