//! Motion-blur algorithms. Each takes a canonical [`Frame`] holding the passes it declared in
//! [`Algorithm::needs`] and returns the blurred colour. Later issues add `reconstruct`
//! (McGuire 2012), `scatter` (Guertin & Nowrouzezahrai) and `stretch` (Wloka) here.

use crate::frame::{Frame, Passes};

/// The blur algorithms shutter knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Algorithm {
    /// Copies colour through unchanged: the whole read/write path with no blur.
    None,
}

impl Algorithm {
    /// Every algorithm, by name, for help texts and messages.
    pub const ALL: &'static [(&'static str, Algorithm)] = &[("none", Algorithm::None)];

    pub fn parse(name: &str) -> Option<Algorithm> {
        Self::ALL
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(name))
            .map(|(_, a)| *a)
    }

    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(_, a)| *a == self)
            .map_or("?", |(n, _)| n)
    }

    /// The passes this algorithm reads; nothing else is decoded.
    pub fn needs(self) -> Passes {
        match self {
            Algorithm::None => Passes::COLOR,
        }
    }
}

/// Parameters shared by every blur.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlurParams {
    /// Fraction of the frame interval the shutter is open (0.5 = 180°), centred on the frame.
    pub shutter: f32,
}

impl Default for BlurParams {
    fn default() -> Self {
        BlurParams { shutter: 0.5 }
    }
}

/// Applies the algorithm to one frame. The output frame holds the blurred colour (other
/// passes are dropped: only colour is written).
pub fn apply(algorithm: Algorithm, _params: &BlurParams, frame: Frame) -> Frame {
    match algorithm {
        Algorithm::None => Frame {
            depth: None,
            velocity: None,
            prev: None,
            next: None,
            ..frame
        },
    }
}
