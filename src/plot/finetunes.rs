//! The figure of a folder of sim-to-real fine-tunings (`quadcl sweep finetunes`): every learned
//! task's performance on the shifted robot before (grey) and after (blue; the fine-tuned task
//! orange) the fine-tuning, one pair of dots joined by a line per seed, so a task whose
//! evaluation did not move shows each seed's line flat.

use super::render::encode_figure_png;
use super::style::{register_font, series_colour, text, CAPTION_SIZE, LABEL_SIZE, TICK_SIZE};
use crate::sweep::finetunes::Finetunes;
use plotters::prelude::*;

/// Pixels per task along the x axis, and the figure's height.
const PER_TASK: u32 = 78;
const HEIGHT: u32 = 520;

/// `table` as a PNG file's bytes.
pub fn finetunes_png(table: &Finetunes) -> anyhow::Result<Vec<u8>> {
    register_font()?;
    let n = table.tasks.len();
    anyhow::ensure!(n > 0, "no task to draw");
    let width = 140 + PER_TASK * n as u32;
    encode_figure_png(width, HEIGHT, |root| {
        let caption = format!(
            "Fine-tuning {} on the shifted robot, {} seeds: each task before (grey) and after (blue; {} orange)",
            table.task,
            table.seeds.len(),
            table.task
        );
        let lowest = table
            .tasks
            .iter()
            .flat_map(|t| t.performance.per_seed.iter().flat_map(|(b, a)| [*b, *a]))
            .fold(0.0f64, f64::min);
        let y0 = if lowest < 0.0 { (lowest * 10.0).floor() / 10.0 } else { 0.0 };
        let mut chart = ChartBuilder::on(root)
            .caption(caption, text(CAPTION_SIZE))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(-0.5..n as f64 - 0.5, y0..1.0)?;
        let names: Vec<String> = table.tasks.iter().map(|t| t.task.clone()).collect();
        chart
            .configure_mesh()
            .x_labels(n)
            .x_label_formatter(&|v: &f64| {
                let i = v.round();
                if (v - i).abs() < 1e-6 && i >= 0.0 {
                    names.get(i as usize).cloned().unwrap_or_default()
                } else {
                    String::new()
                }
            })
            .y_desc("performance on the shifted robot")
            .label_style(text(TICK_SIZE))
            .axis_desc_style(text(LABEL_SIZE))
            .bold_line_style(BLACK.mix(0.08))
            .light_line_style(TRANSPARENT)
            .draw()?;
        let grey = RGBColor(150, 150, 150);
        for (i, task) in table.tasks.iter().enumerate() {
            let after = if task.fine_tuned { series_colour(1) } else { series_colour(0) };
            let seeds = task.performance.per_seed.len().max(1);
            for (k, (before, now)) in task.performance.per_seed.iter().enumerate() {
                // The seeds side by side within the task's slot.
                let x = i as f64 + (k as f64 - (seeds - 1) as f64 / 2.0) * 0.12;
                let (b, a) = ((x - 0.04, *before), (x + 0.04, *now));
                chart.draw_series(std::iter::once(PathElement::new(vec![b, a], grey.mix(0.8).stroke_width(1))))?;
                chart.draw_series(std::iter::once(Circle::new(b, 3, grey.filled())))?;
                chart.draw_series(std::iter::once(Circle::new(a, 3, after.filled())))?;
            }
        }
        Ok(())
    })
}
