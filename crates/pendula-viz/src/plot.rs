//! A study's [`Plot`] (plain data in the library's report) drawn as a [`Figure`]: every
//! study's plots reach PNG and SVG through this one conversion, whichever front end asked.

use pendula::study::{Plot, Style};

use crate::{Bar, Bars, Figure, Kind, Scale, axis_label, method_color, palette};

impl From<&Plot> for Figure {
    /// The plot's axes with their units (catalogue names as symbols), its series in the
    /// palette's order, solid, dashed or as markers.
    fn from(plot: &Plot) -> Self {
        let scale = |log: bool| if log { Scale::Log } else { Scale::Linear };
        if !plot.bars.is_empty() {
            // A bar chart: categories top to bottom, their lengths on the x axis; a method's
            // bar in the method's colour, as in every figure.
            let mut bars =
                Bars::new(plot.title.clone(), axis_label(&plot.x.label, &plot.x.unit), scale(plot.x.log));
            bars.limits = plot.limits;
            for (i, b) in plot.bars.iter().enumerate() {
                let color = if pendula::integrator::find(&b.label).is_ok() {
                    method_color(&b.label)
                } else {
                    palette(i)
                };
                let bar = Bar::new(b.label.clone(), b.value, color, b.note.clone());
                bars.bars.push(Bar { refused: b.refused, ..bar });
            }
            return Figure::from(bars);
        }
        let mut figure = Figure::new(
            crate::labels::greek_words(&plot.title),
            match plot.system {
                Some(system) => crate::labels::system_axis_label(system, &plot.x.label, &plot.x.unit),
                None => axis_label(&plot.x.label, &plot.x.unit),
            },
            axis_label(&crate::labels::greek_words(&plot.y.label), &plot.y.unit),
        )
        .scales(scale(plot.x.log), scale(plot.y.log));
        // An unlabelled series continues the labelled one before it (its simulated markers
        // beside its exact line), in its colour; without a legend the labels only tell
        // series apart by colour.
        let mut color = 0;
        for (i, line) in plot.series.iter().enumerate() {
            if i > 0 && !line.label.is_empty() {
                color += 1;
            }
            let kind = match line.style {
                Style::Solid => Kind::Line,
                Style::Dashed => Kind::Dashed,
                Style::Points => Kind::Markers,
                Style::LineMarkers => Kind::LineMarkers,
                Style::Dots => Kind::Dots,
                Style::Guide => Kind::Guide,
            };
            let label =
                if plot.legend || line.style == Style::Guide { line.label.clone() } else { String::new() };
            let points = line.points.iter().map(|[x, y]| (*x, *y)).collect();
            figure = match (line.style, line.method) {
                // A guide is grey and named on the line; a method's series takes the method's
                // colour and marker, as in every figure.
                (Style::Guide, _) => figure.with(label, crate::GUIDE, kind, points),
                (_, Some(method)) => figure.with_style(label, crate::method_style(method), kind, points),
                _ => figure.with(label, palette(color), kind, points),
            };
        }
        figure
    }
}

#[cfg(test)]
mod tests {
    use pendula::study::{Axis, Line, Plot, Style};

    use crate::{Figure, Kind, Scale};

    #[test]
    fn a_plot_keeps_its_labels_units_scales_and_series() {
        let plot = Plot {
            name: "p",
            title: "a title".into(),
            x: Axis { label: "t".into(), unit: "s".into(), log: false },
            y: Axis { label: "theta1".into(), unit: "rad".into(), log: true },
            bars: Vec::new(),
            limits: None,
            system: None,
            legend: true,
            series: vec![
                Line::new("a", Style::Solid, vec![[0.0, 1.0], [1.0, 2.0]]),
                Line::new("fit", Style::Dashed, vec![[0.0, 1.0]]),
            ],
        };
        let f = Figure::from(&plot);
        assert_eq!(
            (f.title.as_str(), f.x_label.as_str(), f.y_label.as_str()),
            ("a title", "t (s)", "θ₁ (rad)")
        );
        assert_eq!((f.x_scale, f.y_scale), (Scale::Linear, Scale::Log));
        assert_eq!(f.series.len(), 2);
        assert_eq!(f.series[1].kind, Kind::Dashed);
        assert_eq!(f.series[0].points, vec![(0.0, 1.0), (1.0, 2.0)]);
        assert!(f.png().is_ok());
        // An unlabelled series takes the colour of the labelled one before it.
        let mut paired = plot.clone();
        paired.series.insert(1, Line::new("", Style::Points, vec![[0.5, 1.5]]));
        let f = Figure::from(&paired);
        assert_eq!(f.series[0].color, f.series[1].color);
        assert_ne!(f.series[1].color, f.series[2].color);
    }
}
