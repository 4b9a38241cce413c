//! The error-against-time plot (SVG, `plotters`): one panel per region (whole image, fovea, intermediate,
//! periphery), mean FLIP against render time on a logarithmic axis, the uniform sweep as a line and every
//! other configuration as a labelled point.
use plotters::prelude::*;

use super::configs::ConfigKind;
use super::sequence::{BandResult, SequenceReport, SequenceResult};
use super::SceneReport;

const PANELS: [&str; 4] = ["whole image", "fovea", "intermediate", "periphery"];

/// The plot as SVG text.
pub fn plot_svg(r: &SceneReport) -> Result<String, String> {
    let mut svg = String::new();
    draw(r, &mut svg).map_err(|e| format!("plot: {e}"))?;
    Ok(svg)
}

fn draw(r: &SceneReport, svg: &mut String) -> Result<(), Box<dyn std::error::Error>> {
    let root = SVGBackend::with_string(svg, (1400, 1000)).into_drawing_area();
    root.fill(&WHITE)?;
    let root = root.titled(
        &format!(
            "{}: mean FLIP against render time ({}×{}, {}, {:.2} ppd)",
            r.scene_name, r.resolution[0], r.resolution[1], r.backend, r.ppd
        ),
        ("sans-serif", 22),
    )?;
    let times: Vec<f64> = r
        .configs
        .iter()
        .map(|c| c.render_ms)
        .filter(|t| t.is_finite() && *t > 0.0)
        .collect();
    let t_min = times.iter().copied().fold(f64::INFINITY, f64::min);
    let t_max = times.iter().copied().fold(0.0f64, f64::max);
    let (t_min, t_max) = if times.is_empty() {
        (1.0, 10.0)
    } else {
        (t_min / 1.5, t_max * 1.5)
    };

    for (panel, area) in root.split_evenly((2, 2)).iter().enumerate() {
        let value = |c: &super::ConfigResult| c.flip.to_array()[panel];
        let y_max = r
            .configs
            .iter()
            .map(value)
            .filter(|v| v.is_finite())
            .fold(0.0f64, f64::max);
        let y_max = if y_max > 0.0 { y_max * 1.15 } else { 1.0 };
        let mut chart = ChartBuilder::on(area)
            .caption(PANELS[panel], ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(65)
            .build_cartesian_2d((t_min..t_max).log_scale(), 0.0..y_max)?;
        chart
            .configure_mesh()
            .light_line_style(WHITE.mix(0.0))
            .x_desc("render time (ms, log scale)")
            .y_desc("mean FLIP (unitless, 0-1)")
            .y_label_formatter(&|v| format!("{v:.3}"))
            .x_label_formatter(&|v| format!("{v:.0}"))
            .draw()?;

        let finite = |c: &&super::ConfigResult| value(c).is_finite() && c.render_ms > 0.0;
        let sweep: Vec<&super::ConfigResult> = r
            .configs
            .iter()
            .filter(|c| c.spec.kind == ConfigKind::Sweep)
            .filter(finite)
            .collect();
        let blue = RGBColor(40, 90, 200);
        chart
            .draw_series(LineSeries::new(
                sweep.iter().map(|c| (c.render_ms, value(c))),
                blue.stroke_width(2),
            ))?
            .label("uniform sweep (spp)")
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], blue.stroke_width(2))
            });
        chart.draw_series(sweep.iter().map(|c| {
            let spp = c.spec.foveation.spp[0];
            EmptyElement::at((c.render_ms, value(c)))
                + Circle::new((0, 0), 3, blue.filled())
                + Text::new(
                    format!("{spp}"),
                    (4, 4),
                    ("sans-serif", 11).into_font().color(&blue),
                )
        }))?;

        let others: Vec<&super::ConfigResult> = r
            .configs
            .iter()
            .filter(|c| c.spec.kind != ConfigKind::Sweep)
            .filter(finite)
            .collect();
        for (i, c) in others.iter().enumerate() {
            let colour = match c.spec.kind {
                ConfigKind::Uniform => BLACK,
                ConfigKind::EqualTime => RGBColor(20, 150, 60),
                _ => RGBColor(210, 50, 40),
            };
            // Alternate label offsets so neighbouring labels overlap less.
            let dy = if i % 2 == 0 { -14 } else { 6 };
            chart.draw_series(std::iter::once(
                EmptyElement::at((c.render_ms, value(c)))
                    + Circle::new((0, 0), 5, colour.filled())
                    + Text::new(
                        c.spec.name.clone(),
                        (7, dy),
                        ("sans-serif", 12).into_font().color(&colour),
                    ),
            ))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .border_style(BLACK)
            .background_style(WHITE.mix(0.85))
            .draw()?;
    }
    root.present()?;
    Ok(())
}

/// The sequence's plot as SVG text: mean FLIP and flicker against eccentricity (one line per
/// configuration, the region edges marked), and foveal and peripheral FLIP against frame time.
pub fn sequence_svg(scene_name: &str, q: &SequenceReport) -> Result<String, String> {
    let mut svg = String::new();
    draw_sequence(scene_name, q, &mut svg).map_err(|e| format!("plot: {e}"))?;
    Ok(svg)
}

/// A colour per configuration: uniform black, foveated red to orange, the sweep blue; dashed (lighter)
/// without history is not drawable in plotters' SVG, so history gets the full colour and no history a
/// lighter one.
fn sequence_colour(c: &SequenceResult, index: usize) -> RGBColor {
    let base = match c.spec.kind {
        ConfigKind::Uniform => RGBColor(20, 20, 20),
        ConfigKind::Sweep => RGBColor(40, 90, 200),
        ConfigKind::EqualTime => RGBColor(20, 150, 60),
        _ => [
            RGBColor(210, 50, 40),
            RGBColor(220, 130, 20),
            RGBColor(140, 60, 170),
        ][index % 3],
    };
    if c.spec.history {
        base
    } else {
        let lighten = |v: u8| v + (255 - v) / 2;
        RGBColor(lighten(base.0), lighten(base.1), lighten(base.2))
    }
}

/// Long because it draws one SVG in order (axes, grid, each configuration's series, the saccades, the
/// legend), all on the same scales.
fn draw_sequence(
    scene_name: &str,
    q: &SequenceReport,
    svg: &mut String,
) -> Result<(), Box<dyn std::error::Error>> {
    let root = SVGBackend::with_string(svg, (1400, 1000)).into_drawing_area();
    root.fill(&WHITE)?;
    let root = root.titled(
        &format!(
            "{scene_name}: a {}-frame gaze trace, scored around each frame's gaze",
            q.frames
        ),
        ("sans-serif", 22),
    )?;
    let (top, bottom) = root.split_vertically(560);
    let (flip_area, flicker_area) = top.split_horizontally(700);
    let banded: Vec<&SequenceResult> = q
        .results
        .iter()
        .filter(|c| c.spec.kind != ConfigKind::Sweep)
        .collect();
    let max_deg = q
        .results
        .first()
        .and_then(|c| c.bands.last())
        .map_or(1.0, |b| b.to_deg);
    for (area, title, log, get) in [
        (
            &flip_area,
            "mean FLIP against eccentricity",
            false,
            (&|b: &BandResult| b.flip) as &dyn Fn(&BandResult) -> f64,
        ),
        (
            &flicker_area,
            "flicker against eccentricity (log)",
            true,
            &|b: &BandResult| b.flicker,
        ),
    ] {
        let values: Vec<f64> = banded
            .iter()
            .flat_map(|c| c.bands.iter().map(get))
            .filter(|v| v.is_finite() && (!log || *v > 0.0))
            .collect();
        let y_max = values.iter().copied().fold(0.0f64, f64::max);
        let y_min = values.iter().copied().fold(f64::INFINITY, f64::min);
        let mut chart = ChartBuilder::on(area);
        chart
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70);
        let mid = |b: &BandResult| 0.5 * (b.from_deg + b.to_deg);
        if log {
            let (lo, hi) = if values.is_empty() {
                (1e-4, 1.0)
            } else {
                (y_min / 1.5, y_max * 1.5)
            };
            let mut chart = chart.build_cartesian_2d(0.0..max_deg, (lo..hi).log_scale())?;
            chart
                .configure_mesh()
                .x_desc("eccentricity (degrees)")
                .y_desc("flicker")
                .y_label_formatter(&|v| format!("{v:.0e}"))
                .draw()?;
            for bound in q.region_bounds_deg {
                chart.draw_series(LineSeries::new([(bound, lo), (bound, hi)], BLACK.mix(0.3)))?;
            }
            for (i, c) in banded.iter().enumerate() {
                let colour = sequence_colour(c, i);
                chart
                    .draw_series(LineSeries::new(
                        c.bands
                            .iter()
                            .filter(|b| get(b).is_finite() && get(b) > 0.0)
                            .map(|b| (mid(b), get(b))),
                        colour.stroke_width(2),
                    ))?
                    .label(c.spec.name.clone())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
                    });
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::LowerRight)
                .border_style(BLACK)
                .background_style(WHITE.mix(0.85))
                .draw()?;
        } else {
            let hi = if y_max > 0.0 { y_max * 1.15 } else { 1.0 };
            let mut chart = chart.build_cartesian_2d(0.0..max_deg, 0.0..hi)?;
            chart
                .configure_mesh()
                .x_desc("eccentricity (degrees)")
                .y_desc("mean FLIP")
                .y_label_formatter(&|v| format!("{v:.3}"))
                .draw()?;
            for bound in q.region_bounds_deg {
                chart.draw_series(LineSeries::new([(bound, 0.0), (bound, hi)], BLACK.mix(0.3)))?;
            }
            for (i, c) in banded.iter().enumerate() {
                let colour = sequence_colour(c, i);
                chart.draw_series(LineSeries::new(
                    c.bands
                        .iter()
                        .filter(|b| get(b).is_finite())
                        .map(|b| (mid(b), get(b))),
                    colour.stroke_width(2),
                ))?;
            }
        }
    }

    // Equal time: foveal and peripheral FLIP against frame time.
    let (fovea_area, periphery_area) = bottom.split_horizontally(700);
    for (area, title, get) in [
        (
            &fovea_area,
            "foveal FLIP against frame time",
            (&|c: &SequenceResult| c.flip.fovea) as &dyn Fn(&SequenceResult) -> f64,
        ),
        (
            &periphery_area,
            "peripheral FLIP against frame time",
            &|c: &SequenceResult| c.flip.periphery,
        ),
    ] {
        let points: Vec<&SequenceResult> = q
            .results
            .iter()
            .filter(|c| c.frame_ms > 0.0 && c.frame_ms.is_finite() && get(c).is_finite())
            .collect();
        let t_min = points
            .iter()
            .map(|c| c.frame_ms)
            .fold(f64::INFINITY, f64::min);
        let t_max = points.iter().map(|c| c.frame_ms).fold(0.0f64, f64::max);
        let (t_min, t_max) = if points.is_empty() {
            (1.0, 10.0)
        } else {
            (t_min / 1.5, t_max * 1.5)
        };
        let y_max = points.iter().map(|c| get(c)).fold(0.0f64, f64::max);
        let y_max = if y_max > 0.0 { y_max * 1.2 } else { 1.0 };
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d((t_min..t_max).log_scale(), 0.0..y_max)?;
        chart
            .configure_mesh()
            .x_desc("frame time (ms, log scale)")
            .y_desc("mean FLIP")
            .y_label_formatter(&|v| format!("{v:.3}"))
            .x_label_formatter(&|v| format!("{v:.0}"))
            .draw()?;
        for history in [false, true] {
            let sweep: Vec<&&SequenceResult> = points
                .iter()
                .filter(|c| c.spec.kind == ConfigKind::Sweep && c.spec.history == history)
                .collect();
            let blue = if history {
                RGBColor(40, 90, 200)
            } else {
                RGBColor(150, 175, 230)
            };
            chart.draw_series(LineSeries::new(
                sweep.iter().map(|c| (c.frame_ms, get(c))),
                blue.stroke_width(2),
            ))?;
        }
        for (i, c) in points.iter().enumerate() {
            let colour = sequence_colour(c, i);
            let dy = if i % 2 == 0 { -14 } else { 6 };
            chart.draw_series(std::iter::once(
                EmptyElement::at((c.frame_ms, get(c)))
                    + Circle::new((0, 0), 4, colour.filled())
                    + Text::new(
                        c.spec.name.clone(),
                        (6, dy),
                        ("sans-serif", 11).into_font().color(&colour),
                    ),
            ))?;
        }
    }
    root.present()?;
    Ok(())
}
