//! Pictures of spectra and kurtograms, as PNG or SVG, drawn without system fonts.
//!
//! Why: before trusting a verdict such as "outer race, confidence 0.93", a maintenance engineer
//! wants to *see* the envelope spectrum with the fault frequencies and their harmonics marked,
//! which band was demodulated, and the kurtogram that chose it. A picture is checked at a
//! glance where a table of numbers has to be read.
//!
//! How: a [`Figure`] is plain data describing what to show. One layout pass
//! (`scene`, using the axis maths in [`layout`]) turns it into pixel-space primitives; two thin
//! renderers write those as SVG markup or rasterise them with tiny-skia into a PNG. Text in the
//! PNG comes from a built-in public-domain 8×8 bitmap font, drawn at 2× (16 px body text, 24 px
//! titles) so that it reads on a normal screen, so rendering works on a headless
//! edge box with no fonts, no fontconfig and no display.
//!
//! Ours stays, not `plotters`, measured on 2026-11-28 with a scratch "hello plot" (one line
//! series, caption, axis titles, legend; PNG) on plotters 0.3.7, release build, stripped:
//! - text through `ab_glyph` (bitmap backend + encoder): 24 crates, 11 of them new to this
//!   workspace (`image`, `jpeg-decoder`, `ab_glyph`, `ttf-parser`, ...); no system library, but
//!   it draws no text until a TTF is registered: a font file (343 KB for DejaVu Sans Mono)
//!   must ship inside the binary, which came to 1.32 MB.
//! - text through `ttf` (font-kit, the default): 38 crates, 20 new (`font-kit`,
//!   `yeslogic-fontconfig-sys`, `freetype-sys`, `pathfinder_*`, ...); building needs
//!   `libfontconfig1-dev` and `pkg-config` (a Debian apt package; present on this machine,
//!   not on a bare edge box), and the binary (0.93 MB) links `libfontconfig.so.1` and
//!   `libfreetype.so.6` and finds its fonts on the system at run time.
//! - clean release builds of the scratch crate took 6 and 14 minutes of wall time on the
//!   2-core machine shared with other builds (not comparable to an idle machine's figures).
//!
//! Either way the layout (legend, fault markers with staggered labels, tolerance bands, zone
//! lines, kurtogram) would still be ours, its SVG backend would replace only `svg.rs`, and the
//! render tests check our scene's text boxes, which plotters does not expose. Ours needs no
//! new crate (tiny-skia was already here), no font file and no system library.
//!
//! ```no_run
//! use bearingd_lab::plot::{self, Color, Figure, Marker, Series, SpectrumPanel};
//! # fn main() -> Result<(), plot::PlotError> {
//! let freqs: Vec<f64> = (0..2000).map(|i| i as f64 * 0.25).collect();
//! let amplitude: Vec<f64> = freqs.iter().map(|f| (-(f - 105.9f64).powi(2)).exp()).collect();
//! let mut panel = SpectrumPanel::new("frequency (Hz)", "amplitude", freqs);
//! panel.series.push(Series { label: "measured".into(), y: amplitude, color: Color::BLUE });
//! panel.markers.push(Marker { x: 105.9, label: "BPFO".into(), color: Color::VERMILLION, dashed: true });
//! let figure = Figure::new("Envelope spectrum").with_panel(panel);
//! plot::save(&figure, std::path::Path::new("spectrum.png"))?;
//! # Ok(()) }
//! ```

mod figure;
pub mod layout;
mod png;
mod scene;
mod svg;

use std::path::{Path, PathBuf};

pub use figure::{
    Color, Figure, HeatmapPanel, HeatmapRow, LegendEntry, LegendSample, Level, Marker, Panel,
    Series, Shade, SpectrumPanel,
};

/// File extensions [`save`] understands, lower case and without the dot.
pub const SUPPORTED_EXTENSIONS: [&str; 2] = ["png", "svg"];

/// Why a figure could not be drawn or written.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    #[error("the figure has no panels: nothing to draw")]
    NoPanels,
    #[error("the figure has {count} panels; at most {max} fit in one image")]
    TooManyPanels { count: usize, max: usize },
    #[error(
        "cannot tell which image format to write for {}: the file name must end in .png or .svg",
        path.display()
    )]
    UnsupportedExtension { path: PathBuf },
    #[error("cannot allocate a {width}×{height} pixel canvas")]
    Canvas { width: u32, height: u32 },
    #[error("PNG encoding failed: {0}")]
    PngEncode(String),
    #[error("cannot write {}: {source}", path.display())]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// The image formats a figure can be written in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageFormat {
    Png,
    Svg,
}

impl ImageFormat {
    /// The format named by `path`'s extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Self, PlotError> {
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match extension.as_deref() {
            Some("png") => Ok(ImageFormat::Png),
            Some("svg") => Ok(ImageFormat::Svg),
            _ => Err(PlotError::UnsupportedExtension {
                path: path.to_path_buf(),
            }),
        }
    }
}

/// Where a line of text lands on the canvas, in pixels (y down).
#[doc(hidden)]
#[derive(Debug, Clone, PartialEq)]
pub struct TextBox {
    pub content: String,
    pub left: f64,
    pub top: f64,
    pub right: f64,
    pub bottom: f64,
}

/// For layout tests: the canvas size of `figure` and the box of every non-empty text in it.
#[doc(hidden)]
pub fn text_boxes(figure: &Figure) -> Result<(u32, u32, Vec<TextBox>), PlotError> {
    let scene = scene::build(figure)?;
    let boxes = scene.text_boxes();
    Ok((scene.width, scene.height, boxes))
}

/// Renders `figure` as an SVG document.
pub fn render_svg(figure: &Figure) -> Result<String, PlotError> {
    Ok(svg::write_svg(&scene::build(figure)?))
}

/// Renders `figure` as PNG file bytes.
pub fn render_png(figure: &Figure) -> Result<Vec<u8>, PlotError> {
    png::encode_png(&scene::build(figure)?)
}

/// Renders `figure` and writes it to `path`, as PNG or SVG according to the extension.
pub fn save(figure: &Figure, path: &Path) -> Result<(), PlotError> {
    let bytes = match ImageFormat::from_path(path)? {
        ImageFormat::Png => render_png(figure)?,
        ImageFormat::Svg => render_svg(figure)?.into_bytes(),
    };
    std::fs::write(path, bytes).map_err(|source| PlotError::Write {
        path: path.to_path_buf(),
        source,
    })
}
