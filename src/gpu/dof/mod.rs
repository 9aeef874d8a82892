//! Depth of field's GPU twins, mirroring [`crate::dof`]: `coc`, tile min/max (`tiles`), the
//! bokeh `gather` and `blend`'s pyramid.

pub mod blend;
pub mod coc;
pub mod gather;
pub mod tiles;
