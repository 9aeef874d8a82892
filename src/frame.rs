//! The planar passes of one frame, in the canonical convention of docs/DESIGN.md:
//!
//! - pixel (i, j) has its centre at (i + 0.5, j + 0.5); x grows right, y grows down;
//! - colour is scene-linear RGB(A), premultiplied alpha, f32;
//! - depth is positive linear distance along the view axis; `inf` means far;
//! - velocity `v = p(0) - p(-1)` in pixels per frame;
//! - `prev`/`next` are absolute screen positions p(-1)/p(+1) in pixels (x, y, optional z).
//!
//! Every plane is a row-major `Vec<f32>` of `width * height` samples. A pass that was not
//! asked for is `None`: readers never decode what the operation does not use.

/// One channel of one pass, row-major, `width * height` samples.
pub type Plane = Vec<f32>;

/// A plane of `n` zeros, or an error when the system refuses the memory (the allocation is
/// fallible: no abort).
pub fn try_plane(n: usize) -> Result<Plane, String> {
    let mut plane = Plane::new();
    plane.try_reserve_exact(n).map_err(|e| {
        format!(
            "cannot allocate a plane of {n} samples ({} MiB): {e}",
            (n as u64 * 4).div_ceil(1 << 20)
        )
    })?;
    plane.resize(n, 0.0);
    Ok(plane)
}

/// The screen position of the centre of pixel `index` of a row-major image `width` wide.
pub fn pixel_centre(index: usize, width: usize) -> (f32, f32) {
    ((index % width) as f32 + 0.5, (index / width) as f32 + 0.5)
}

/// Which passes an operation needs. Readers decode exactly these.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Passes {
    pub color: bool,
    pub depth: bool,
    pub velocity: bool,
    pub prev: bool,
    pub next: bool,
}

impl Passes {
    pub const COLOR: Passes = Passes {
        color: true,
        depth: false,
        velocity: false,
        prev: false,
        next: false,
    };
    pub const ALL: Passes = Passes {
        color: true,
        depth: true,
        velocity: true,
        prev: true,
        next: true,
    };

    /// The passes either needs.
    pub fn union(self, other: Passes) -> Passes {
        Passes {
            color: self.color || other.color,
            depth: self.depth || other.depth,
            velocity: self.velocity || other.velocity,
            prev: self.prev || other.prev,
            next: self.next || other.next,
        }
    }

    /// The names of the passes that are set, in canonical order.
    pub fn names(self) -> Vec<&'static str> {
        let mut names = Vec::new();
        for (set, name) in [
            (self.color, "color"),
            (self.depth, "depth"),
            (self.velocity, "velocity"),
            (self.prev, "prev"),
            (self.next, "next"),
        ] {
            if set {
                names.push(name);
            }
        }
        names
    }
}

/// Colour: R, G, B and an optional alpha.
#[derive(Clone, Debug, PartialEq)]
pub struct Color {
    pub r: Plane,
    pub g: Plane,
    pub b: Plane,
    pub a: Option<Plane>,
}

impl Color {
    /// A colour of no pixels: what stands in a colour's place while it is moved out.
    pub fn empty() -> Color {
        Color {
            r: Vec::new(),
            g: Vec::new(),
            b: Vec::new(),
            a: None,
        }
    }

    /// The planes present: R, G, B, then alpha where there is one.
    pub fn planes(&self) -> Vec<&[f32]> {
        [Some(&self.r), Some(&self.g), Some(&self.b), self.a.as_ref()]
            .into_iter()
            .flatten()
            .map(|p| p.as_slice())
            .collect()
    }
}

/// Absolute screen positions of the surface seen at each pixel, in pixels; `z` is its depth
/// at that time when the renderer gives one.
#[derive(Clone, Debug, PartialEq)]
pub struct Positions {
    pub x: Plane,
    pub y: Plane,
    pub z: Option<Plane>,
}

/// Velocity `p(0) - p(-1)` in pixels per frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Velocity {
    pub x: Plane,
    pub y: Plane,
}

/// Where the pixels sit in the file's coordinate space, kept so outputs keep the input's
/// data and display windows (overscan, crops).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Windows {
    /// Top-left corner of the data window.
    pub data_origin: (i32, i32),
    /// The display window: the picture, in the file's coordinates.
    pub display: Window,
}

/// A rectangle of the file's pixel coordinates: its top-left corner and its size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Window {
    pub x: i32,
    pub y: i32,
    pub width: usize,
    pub height: usize,
}

impl Window {
    /// `plane` (this window's samples) placed on `to`: what `to` holds of it, the default (0)
    /// where it does not reach.
    pub fn place<T: Copy + Default>(&self, plane: &[T], to: &Window) -> Vec<T> {
        if self == to {
            return plane.to_vec();
        }
        let mut out = vec![T::default(); to.width * to.height];
        let end = |w: &Window| {
            (
                i64::from(w.x) + w.width as i64,
                i64::from(w.y) + w.height as i64,
            )
        };
        let (end, to_end) = (end(self), end(to));
        let x0 = i64::from(self.x).max(i64::from(to.x));
        let x1 = end.0.min(to_end.0);
        let y0 = i64::from(self.y).max(i64::from(to.y));
        let y1 = end.1.min(to_end.1);
        if x0 >= x1 {
            return out;
        }
        let n = (x1 - x0) as usize;
        for y in y0..y1 {
            let from =
                (y - i64::from(self.y)) as usize * self.width + (x0 - i64::from(self.x)) as usize;
            let at = (y - i64::from(to.y)) as usize * to.width + (x0 - i64::from(to.x)) as usize;
            out[at..at + n].copy_from_slice(&plane[from..from + n]);
        }
        out
    }

    /// The last pixel's coordinates (inclusive), as EXR headers and `shutter info` give them.
    pub fn max(&self) -> (i32, i32) {
        (
            self.x + self.width as i32 - 1,
            self.y + self.height as i32 - 1,
        )
    }
}

impl Windows {
    pub fn full(width: usize, height: usize) -> Self {
        Windows {
            data_origin: (0, 0),
            display: Window {
                x: 0,
                y: 0,
                width,
                height,
            },
        }
    }

    /// A plane of `width × height` samples over the data window, as the display window shows
    /// it: what lies outside the display is cut off, what the data does not cover is 0.
    pub fn on_display(&self, plane: &[f32], width: usize, height: usize) -> Vec<f32> {
        let (x, y) = self.data_origin;
        let data = Window {
            x,
            y,
            width,
            height,
        };
        data.place(plane, &self.display)
    }
}

/// The passes of one frame. All present planes have `width * height` samples.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    pub width: usize,
    pub height: usize,
    pub windows: Windows,
    pub color: Option<Color>,
    pub depth: Option<Plane>,
    pub velocity: Option<Velocity>,
    pub prev: Option<Positions>,
    pub next: Option<Positions>,
    /// What the colour file holds besides the passes, given back to the output.
    pub carried: Carried,
}

/// What a frame brings from its colour file besides the passes and gives back to its output,
/// untouched by them (issue 29: what comes in goes out). The passes keep it as it is: each
/// returns the frame it was given with new colour.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Carried {
    /// An 8/16-bit colour file's profile and metadata (`io::image` reads and writes them).
    pub photo: Option<Photo>,
    /// An EXR colour file's headers, every part's: the output is made like them (attributes
    /// and form: compression, line order, blocks, each channel's pixel type), part for part.
    pub headers: Vec<exr::meta::header::Header>,
    /// Which of `headers` holds the beauty.
    pub colour_part: usize,
    /// The names the beauty's channels had in the colour file (R, G, B and A when empty):
    /// an EXR output names them so again.
    pub beauty: Vec<String>,
    /// The same names as stored, view and all (`right.R` where `beauty` says `R`): what a
    /// multi-view output names each view's beauty.
    pub beauty_stored: Vec<String>,
    /// Every other channel of the colour file's part, in its order, with its class
    /// (`io::channels`): colour channels are blurred with the beauty's weights, data channels
    /// come back as they were read.
    pub channels: Vec<CarriedChannel>,
    /// The beauty is a stack's merge of its layers (`stack::merge`): a multi-part EXR output
    /// gives it a part of its own (`io::exr_parts`).
    pub merged: bool,
    /// A merged beauty's channels (R, G, B, A): for each, the name in the first layer's
    /// colour part whose pixel type it is written in, where every layer stores that channel
    /// of its beauty in one type (`stack::merge`); else none (float, or the part's own).
    pub merged_like: Vec<Option<String>>,
}

/// What a carried channel holds ([`crate::io::channels`] sorts them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayerClass {
    /// Light (`diffuse.R`, `specular.A`): blurred with exactly the weights the beauty gets.
    Colour,
    /// A description of the surface (depth, vectors, normals, IDs): passed through unchanged.
    Data,
    /// Data carried with the motion (a preset's `[layers]` asks): each pixel takes the value
    /// of the nearest surface whose streak covers it over the exposure
    /// ([`crate::motion::carry`]); unchanged by depth of field.
    Motion,
}

impl LayerClass {
    pub fn name(self) -> &'static str {
        match self {
            LayerClass::Colour => "colour",
            LayerClass::Data => "data",
            LayerClass::Motion => "motion",
        }
    }

    /// Whether the class holds data (values never mixed: passed through, or carried with the
    /// motion), not light.
    pub fn is_data(self) -> bool {
        self != LayerClass::Colour
    }
}

/// A channel of the colour file besides the beauty's, carried to the output.
#[derive(Clone, Debug, PartialEq)]
pub struct CarriedChannel {
    /// Its name as the view read sees it (`diffuse.R`; in a file of no views, as stored).
    pub name: String,
    /// Its name as stored, view and all (`diffuse.right.R`): what a multi-view output
    /// writes.
    pub stored: String,
    /// A channel of no view in a multi-view file: every view reads it, a multi-view output
    /// writes it once.
    pub shared: bool,
    /// The part of the colour file it is stored in.
    pub part: usize,
    pub class: LayerClass,
    pub plane: Plane,
    /// A u32 channel's values exactly as stored (`plane` holds them as f32, rounded over
    /// 2²⁴): what an output of u32 channels writes back. Always data.
    pub exact: Option<Vec<u32>>,
    /// The data window of a part of data passed through at its own window, not the
    /// beauty's (`plane` is its size); `None`: the frame's.
    pub window: Option<Window>,
}

/// One of a PNG's text chunks: a keyword (`Comment`, `Software`, `parameters`) and its text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PngText {
    pub keyword: String,
    pub text: String,
    /// tEXt (Latin-1), zTXt (Latin-1, compressed) or iTXt (UTF-8).
    pub kind: TextKind,
    /// An iTXt's language tag (`en`, `de-CH`) and its keyword translated into that language
    /// (empty where none, and for tEXt and zTXt).
    pub language: String,
    pub translated: String,
}

/// The chunk a PNG text came in, and goes out in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextKind {
    Latin1,
    Compressed,
    International,
}

/// A photo's pixel density, as its file stores it beside the pixels (a JPEG's JFIF density, a
/// PNG's pHYs, a TIFF's XResolution, YResolution and ResolutionUnit), of the upright pixels:
/// pixels per unit along x and y, each a ratio (numerator, denominator) as a TIFF stores it
/// (over 1 from JFIF and pHYs, which store whole numbers).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Resolution {
    pub x: (u32, u32),
    pub y: (u32, u32),
    pub unit: ResolutionUnit,
}

/// The unit of a [`Resolution`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ResolutionUnit {
    /// No unit: x and y give the pixels' aspect ratio alone.
    None,
    Inch,
    Centimetre,
    /// A PNG's unit.
    Metre,
}

/// A PNG's colour chunks besides iCCP, as stored: gAMA (the encoding gamma × 100000: 45455
/// for codes that are light^(1/2.2)), cHRM (white, red, green and blue x, y, each × 100000),
/// sRGB (its rendering intent) and cICP (ITU-T H.273's colour primaries, transfer
/// characteristics and matrix coefficients, and 1 for full-range codes). A cICP says how
/// the codes are coded over every other chunk; where the PNG has none, no iCCP and no sRGB
/// chunk, gAMA and cHRM say it (`io::image::profile_of`); a PNG output holds them again.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PngColour {
    pub gamma: Option<u32>,
    pub chromaticities: Option<[u32; 8]>,
    pub srgb: Option<u8>,
    pub cicp: Option<[u8; 4]>,
    /// The matrix coefficients the file's cICP gave where they were not 0 (PNG's samples are
    /// RGB: 0), which shutter reads as 0 (`cicp` holds 0; `io::image::png_mend`).
    pub cicp_matrix_read_as_0: Option<u8>,
}

/// The metadata of an 8/16-bit photo, as its file stores it, so the output holds it again.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Photo {
    /// The embedded ICC profile (its bytes as stored).
    pub icc: Option<Vec<u8>>,
    /// EXIF (a TIFF structure), XMP (the XML packet) and IPTC (a JPEG's Photoshop resource
    /// blocks), as stored, but for the orientation, which says 1: the frame holds the photo
    /// turned upright.
    pub exif: Option<Vec<u8>>,
    pub xmp: Option<Vec<u8>>,
    pub iptc: Option<Vec<u8>>,
    /// A PNG's text chunks (tEXt, zTXt, iTXt; XMP's iTXt is `xmp`), in file order: written
    /// again to a PNG output.
    pub texts: Vec<PngText>,
    /// Bits per sample of the input: 8 or 16, or 32 for a float TIFF (whose values are read
    /// as linear light, not through a profile's curves).
    pub bits: u8,
    /// The input is grey (one channel, or grey and alpha): a grey output holds it again.
    pub grey: bool,
    /// A JPEG's chroma subsampling: its luma sampling factors over its chroma's, (2, 2) for
    /// 4:2:0, (1, 1) for 4:4:4; `None` for other files.
    pub sampling: Option<(u8, u8)>,
    /// A PNG's gAMA, cHRM and sRGB chunks, where it has any.
    pub png_colour: Option<PngColour>,
    /// Its pixel density, where the file gives one (and not only square pixels).
    pub resolution: Option<Resolution>,
    /// The file's colour is premultiplied by its alpha (a TIFF whose ExtraSamples says
    /// associated alpha): the read divides it out before anything else. Outputs are written
    /// with straight alpha, declared as such, whatever the input held.
    pub premultiplied: bool,
    /// The file's alpha is unassociated (a TIFF whose ExtraSamples says 2): a float TIFF's
    /// colour, which is read as it is stored, is premultiplied on read (an 8/16-bit photo's
    /// always is).
    pub straight: bool,
    /// A TIFF holding more images after its first (pages, or a reduced-size preview): only
    /// the first is read and written, and the run says so.
    pub more_images: bool,
    /// The straight colour (linear) of the pixels alpha 0 hides, where it is not black:
    /// premultiplying on read loses it, and an output pixel that nothing covers (alpha 0
    /// still) holds it again (a cut-out's background, a texture's bleed), as Pillow keeps it.
    pub hidden: Option<Hidden>,
}

/// The straight colour under a photo's alpha 0 ([`Photo::hidden`]): the frame's size, and
/// each such pixel's index with its R, G and B.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Hidden {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<(u32, [f32; 3])>,
}

impl Frame {
    /// An empty frame of the given size: no passes yet.
    pub fn new(width: usize, height: usize) -> Self {
        Frame {
            width,
            height,
            windows: Windows::full(width, height),
            color: None,
            depth: None,
            velocity: None,
            prev: None,
            next: None,
            carried: Carried::default(),
        }
    }

    /// The frame's size and passes without its colour or what it carries: what a colour
    /// layer is blurred with in the beauty's place.
    pub fn clone_passes(&self) -> Frame {
        Frame {
            width: self.width,
            height: self.height,
            windows: self.windows,
            color: None,
            depth: self.depth.clone(),
            velocity: self.velocity.clone(),
            prev: self.prev.clone(),
            next: self.next.clone(),
            carried: Carried::default(),
        }
    }

    pub fn pixel_count(&self) -> usize {
        self.width * self.height
    }

    /// The screen position of the centre of pixel `index` (row-major).
    pub fn pixel_centre(&self, index: usize) -> (f32, f32) {
        pixel_centre(index, self.width)
    }

    /// Bytes held by the decoded planes (for memory accounting).
    pub fn decoded_bytes(&self) -> usize {
        let planes = self
            .color
            .as_ref()
            .map_or(0, |c| 3 + c.a.is_some() as usize)
            + self.depth.is_some() as usize
            + 2 * self.velocity.is_some() as usize
            + self.prev.as_ref().map_or(0, |p| 2 + p.z.is_some() as usize)
            + self.next.as_ref().map_or(0, |p| 2 + p.z.is_some() as usize);
        planes * self.pixel_count() * std::mem::size_of::<f32>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plane_placed_on_another_window_keeps_what_overlaps_and_is_0_elsewhere() {
        let w = |x, y, width, height| Window {
            x,
            y,
            width,
            height,
        };
        // 3×2 at (-1, 1): values 1..=6.
        let from = w(-1, 1, 3, 2);
        let plane = [1, 2, 3, 4, 5, 6];
        // Onto 2×3 at (0, 0): row 0 uncovered; rows 1 and 2 take columns 0 and 1 of the
        // plane's x = 0, 1 (its second and third columns).
        assert_eq!(from.place(&plane, &w(0, 0, 2, 3)), [0, 0, 2, 3, 5, 6]);
        // No overlap at all: all 0; the same window: the plane itself.
        assert_eq!(from.place(&plane, &w(5, 5, 2, 1)), [0, 0]);
        assert_eq!(from.place(&plane, &from), plane);
    }

    #[test]
    fn pixel_centres_are_at_half_integers_y_down() {
        let frame = Frame::new(4, 3);
        assert_eq!(frame.pixel_centre(0), (0.5, 0.5));
        assert_eq!(frame.pixel_centre(5), (1.5, 1.5));
        assert_eq!(frame.pixel_centre(11), (3.5, 2.5));
    }

    #[test]
    fn passes_names_in_canonical_order() {
        assert_eq!(
            Passes::ALL.names(),
            ["color", "depth", "velocity", "prev", "next"]
        );
        assert_eq!(Passes::COLOR.names(), ["color"]);
    }
}
