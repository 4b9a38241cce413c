//! The error-against-time plot (SVG, `plotters`): one panel per region (whole image, fovea, intermediate,
//! periphery), mean FLIP against render time on a logarithmic axis, the uniform sweep as a line and every
//! other configuration as a labelled point.
use plotters::prelude::*;

use super::configs::ConfigKind;
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
