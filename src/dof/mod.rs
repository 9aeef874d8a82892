//! Depth of field (issue 7, in progress): the circle of confusion so far; the blurriness
//! blend and the bokeh gather build on it.

pub mod coc;
