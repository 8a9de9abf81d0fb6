//! Renders a synthetic diagnosis figure to SVG and PNG and checks what comes out.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

use bearingd_lab::plot::{
    self, Color, Figure, HeatmapPanel, HeatmapRow, Marker, PlotError, Series, Shade, SpectrumPanel,
};
use tiny_skia::Pixmap;

const BPFO: f64 = 105.9;
const SHAFT: f64 = 29.95;

/// Deterministic noise in [0, 1).
fn noise(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6_364_136_223_846_793_005)
        .wrapping_add(1_442_695_040_888_963_407);
    (*seed >> 11) as f64 / (1u64 << 53) as f64
}

fn peak(f: f64, centre: f64, height: f64) -> f64 {
    height * (-((f - centre) / 0.6).powi(2)).exp()
}

fn envelope_spectrum_panel() -> SpectrumPanel {
    let resolution = 0.1;
    let x: Vec<f64> = (0..6000).map(|i| i as f64 * resolution).collect();
    let mut seed = 7;
    let measured: Vec<f64> = x
        .iter()
        .map(|&f| {
            let mut a = 0.004 + 0.004 * noise(&mut seed);
            a += peak(f, SHAFT, 0.015);
            for (k, h) in [(1.0, 0.12), (2.0, 0.07), (3.0, 0.035), (4.0, 0.02)] {
                a += peak(f, k * BPFO, h);
                a += peak(f, k * BPFO - SHAFT, h * 0.2) + peak(f, k * BPFO + SHAFT, h * 0.2);
            }
            a
        })
        .collect();
    let twin: Vec<f64> = x
        .iter()
        .map(|&f| {
            [(1.0, 0.11), (2.0, 0.06), (3.0, 0.03), (4.0, 0.018)]
                .iter()
                .map(|&(k, h)| peak(f, k * BPFO, h))
                .sum::<f64>()
                + 0.005
        })
        .collect();

    let mut panel = SpectrumPanel::new("frequency (Hz)", "envelope amplitude (g)", x);
    panel.series = vec![
        Series {
            label: "measured".into(),
            y: measured,
            color: Color::BLUE,
        },
        Series {
            label: "twin (outer race)".into(),
            y: twin,
            color: Color::VERMILLION.with_alpha(200),
        },
    ];
    for (k, x) in [(1, 105.9), (2, 211.8), (3, 317.6), (4, 423.5)] {
        let label = if k == 1 {
            "BPFO".to_string()
        } else {
            format!("{k}×BPFO")
        };
        panel.markers.push(Marker {
            x,
            label,
            color: Color::VERMILLION,
            dashed: k > 1,
        });
        panel.shaded.push(Shade {
            x0: x * 0.98,
            x1: x * 1.02,
            color: Color::VERMILLION.with_alpha(30),
        });
    }
    panel.markers.push(Marker {
        x: SHAFT,
        label: "shaft".into(),
        color: Color::GREY,
        dashed: true,
    });
    panel.markers.push(Marker {
        x: 5.0 * BPFO,
        label: "5×BPFO".into(),
        color: Color::VERMILLION,
        dashed: true,
    });
    panel.markers.push(Marker {
        x: 156.1,
        label: "BPFI".into(),
        color: Color::BLUISH_GREEN,
        dashed: true,
    });
    panel.markers.push(Marker {
        x: 141.2,
        label: "2×BSF".into(),
        color: Color::REDDISH_PURPLE,
        dashed: true,
    });
    panel.x_range = Some((0.0, 550.0));
    panel
}

fn kurtogram_panel() -> HeatmapPanel {
    // A made-up kurtogram whose best band is 2000–4000 Hz at level 1.6.
    let levels = [("0", 1), ("1", 2), ("1.6", 3), ("2", 4), ("2.6", 6)];
    let rows = levels
        .iter()
        .map(|&(label, cells)| {
            let bandwidth = 6000.0 / cells as f64;
            let width_fit = (-(bandwidth / 2000.0_f64).log2().powi(2) / 0.5).exp();
            HeatmapRow {
                label: label.into(),
                values: (0..cells)
                    .map(|c| {
                        let centre = (c as f64 + 0.5) * bandwidth;
                        let centre_fit = (-((centre - 3000.0) / 1200.0).powi(2)).exp();
                        2.7 * centre_fit * width_fit
                    })
                    .collect(),
            }
        })
        .collect();
    HeatmapPanel {
        title: "Fast kurtogram (band selection)".into(),
        x_label: "frequency (Hz)".into(),
        x_max: 6000.0,
        rows,
        highlight: Some((2, 1)),
        value_label: "GK index".into(),
        y_label: "level".into(),
    }
}

fn diagnosis_figure() -> Figure {
    Figure::new("Bearing 6205-2RS, drive end — envelope spectrum")
        .with_note("band 2000–4000 Hz (GK index 2.7), fs 12 kHz, 10 s")
        .with_note("diagnosis: outer_race, confidence 0.93")
        .with_panel(envelope_spectrum_panel())
        .with_panel(kurtogram_panel())
}

/// Width and height from a PNG's IHDR chunk.
fn png_dimensions(bytes: &[u8]) -> (u32, u32) {
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    (be(&bytes[16..20]), be(&bytes[20..24]))
}

#[test]
fn svg_contains_title_markers_and_labels() {
    let svg = plot::render_svg(&diagnosis_figure()).unwrap();
    assert!(svg.starts_with("<svg"));
    assert!(svg.trim_end().ends_with("</svg>"));
    for expected in [
        "Bearing 6205-2RS",
        ">BPFO<",
        ">2×BPFO<",
        ">3×BPFO<",
        "GK index",
        "measured",
        "diagnosis: outer_race",
    ] {
        assert!(svg.contains(expected), "missing {expected:?}");
    }
    // Balanced tags, roughly: every element is self-closed or closed.
    assert_eq!(svg.matches("<text").count(), svg.matches("</text>").count());
    std::fs::write(std::env::temp_dir().join("bearingd_plot_example.svg"), &svg).unwrap();
}

#[test]
fn svg_escapes_markup_in_labels() {
    let mut panel = SpectrumPanel::new("f <Hz>", "a & b", vec![1.0, 2.0]);
    panel.series.push(Series {
        label: "\"quoted\"".into(),
        y: vec![1.0, 2.0],
        color: Color::BLUE,
    });
    let svg = plot::render_svg(&Figure::new("<script>").with_panel(panel)).unwrap();
    assert!(!svg.contains("<script>"));
    assert!(svg.contains("&lt;script&gt;"));
    assert!(svg.contains("a &amp; b"));
}

#[test]
fn png_decodes_with_expected_size_and_drawn_plot() {
    let figure = diagnosis_figure();
    let bytes = plot::render_png(&figure).unwrap();
    let (width, height) = png_dimensions(&bytes);
    assert_eq!(width, 1600);
    assert!(
        height > 2 * 480 && height < 2 * 480 + 300,
        "height {height}"
    );
    let pixmap = Pixmap::decode_png(&bytes).unwrap();
    assert_eq!((pixmap.width(), pixmap.height()), (width, height));

    // Inside the first panel's plot area there are blue (series) pixels.
    let blue = pixmap
        .pixels()
        .iter()
        .enumerate()
        .filter(|(i, _)| {
            let (x, y) = ((*i as u32) % width, (*i as u32) / width);
            (200..1500).contains(&x) && (200..500).contains(&y)
        })
        .filter(|(_, p)| p.blue() > 120 && p.red() < 80)
        .count();
    assert!(blue > 200, "only {blue} series pixels");
    std::fs::write(
        std::env::temp_dir().join("bearingd_plot_example.png"),
        &bytes,
    )
    .unwrap();
}

#[test]
fn single_sample_spike_survives_decimation() {
    // 200 000 samples into about 1 000 pixel columns: one sample in 200 is drawn at most, and
    // the lone spike must still reach the top of the plot.
    let n = 200_000;
    let x: Vec<f64> = (0..n).map(|i| i as f64).collect();
    let mut y = vec![0.0; n];
    let spike = 123_457;
    y[spike] = 1.0;
    let marker_colour = Color::rgb(255, 0, 255);
    let mut panel = SpectrumPanel::new("", "", x);
    panel.series.push(Series {
        label: String::new(),
        y,
        color: marker_colour,
    });
    let bytes = plot::render_png(&Figure::new("").with_panel(panel)).unwrap();
    let pixmap = Pixmap::decode_png(&bytes).unwrap();

    let series_pixels: Vec<(u32, u32)> = (0..pixmap.height())
        .flat_map(|y| (0..pixmap.width()).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            pixmap
                .pixel(x, y)
                .is_some_and(|p| p.red() > 200 && p.blue() > 200 && p.green() < 60)
        })
        .collect();
    let baseline = series_pixels
        .iter()
        .map(|&(_, y)| y)
        .max()
        .expect("series drawn");
    let (top_x, top_y) = *series_pixels.iter().min_by_key(|&&(_, y)| y).unwrap();
    let (plot_left, plot_right) = (176.0, 1600.0 - 40.0);
    let expected_x = plot_left + spike as f64 / n as f64 * (plot_right - plot_left);
    assert!(
        (f64::from(top_x) - expected_x).abs() < 2.0,
        "spike drawn at column {top_x}, expected {expected_x}"
    );
    assert!(
        baseline - top_y > 250,
        "spike only {} px tall",
        baseline - top_y
    );
}

#[test]
fn hostile_inputs_do_not_panic() {
    let mut panel = SpectrumPanel::new("x", "y", vec![f64::NAN, 1.0, f64::INFINITY, 3.0]);
    panel.series = vec![
        Series {
            label: "nan".into(),
            y: vec![f64::NAN; 4],
            color: Color::BLUE,
        },
        Series {
            label: "short".into(),
            y: vec![1.0],
            color: Color::ORANGE,
        },
        Series {
            label: "empty".into(),
            y: vec![],
            color: Color::BLACK,
        },
        Series {
            label: "huge".into(),
            y: vec![1e308, -1e308, 0.0, 5.0],
            color: Color::BLACK,
        },
    ];
    panel.markers.push(Marker {
        x: f64::NAN,
        label: "nan".into(),
        color: Color::BLACK,
        dashed: false,
    });
    panel.shaded.push(Shade {
        x0: f64::INFINITY,
        x1: 2.0,
        color: Color::GREY,
    });
    let mut log_panel = panel.clone();
    log_panel.log_y = true;
    let mut outside = panel.clone();
    outside.x_range = Some((1e6, 2e6));
    let mut reversed = panel.clone();
    reversed.x_range = Some((3.0, f64::NAN));
    let mut empty = SpectrumPanel::new("", "", vec![]);
    empty.markers = (0..200)
        .map(|i| Marker {
            x: i as f64 * 0.001,
            label: "crowded label".repeat(20),
            color: Color::BLUE,
            dashed: true,
        })
        .collect();
    empty.x_range = Some((0.0, 0.2));
    let heatmap = HeatmapPanel {
        title: String::new(),
        x_label: String::new(),
        x_max: f64::NAN,
        rows: vec![
            HeatmapRow {
                label: "a".into(),
                values: vec![],
            },
            HeatmapRow {
                label: "b".into(),
                values: vec![f64::NAN, 1.0, f64::NEG_INFINITY],
            },
            HeatmapRow {
                label: "c".into(),
                values: vec![2.0; 50_000],
            },
        ],
        highlight: Some((7, 9)),
        value_label: String::new(),
        y_label: String::new(),
    };
    let no_rows = HeatmapPanel {
        rows: vec![],
        highlight: Some((0, 0)),
        ..heatmap.clone()
    };
    let figure = Figure {
        title: "x".repeat(1000),
        notes: vec!["note".into(); 100],
        panels: vec![
            panel.into(),
            log_panel.into(),
            outside.into(),
            reversed.into(),
            empty.into(),
            heatmap.into(),
            no_rows.into(),
        ],
    };
    assert!(plot::render_svg(&figure).is_ok());
    let bytes = plot::render_png(&figure).unwrap();
    assert!(Pixmap::decode_png(&bytes).is_ok());
}

#[test]
fn figure_without_panels_is_an_error() {
    let figure = Figure::new("empty");
    assert!(matches!(
        plot::render_png(&figure),
        Err(PlotError::NoPanels)
    ));
    assert!(matches!(
        plot::render_svg(&figure),
        Err(PlotError::NoPanels)
    ));
}

#[test]
fn save_chooses_format_by_extension() {
    let dir = std::env::temp_dir().join(format!("bearingd_plot_save_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let figure = diagnosis_figure();

    plot::save(&figure, &dir.join("a.PNG")).unwrap();
    let png = std::fs::read(dir.join("a.PNG")).unwrap();
    assert_eq!(&png[1..4], b"PNG");

    plot::save(&figure, &dir.join("a.svg")).unwrap();
    let svg = std::fs::read_to_string(dir.join("a.svg")).unwrap();
    assert!(svg.starts_with("<svg"));

    let err = plot::save(&figure, Path::new("out/figure.jpg")).unwrap_err();
    let message = err.to_string();
    assert!(message.contains("out/figure.jpg"), "{message}");
    assert!(
        message.contains(".png") && message.contains(".svg"),
        "{message}"
    );
    assert!(plot::save(&figure, Path::new("no_extension")).is_err());

    std::fs::remove_dir_all(&dir).unwrap();
}
