//! What a run shows a person: line plots, isometric pictures of designs and the report document
//! (Markdown and HTML) they go into. Tasks draw their own figures with these; the fabrication
//! exports and the physics know nothing of them.

mod document;
mod plot;
mod render;

pub use document::{Block, Link, Picture, Report};
pub use plot::{PlotSpec, Series, line_plot, line_plot_over};
pub(crate) use plot::{line, text};
pub(crate) use render::fill_quad;
pub use render::{Image, render_isometric};
