//! A sequence chart: one lifeline per participant, each step a bar across the
//! participants it synchronises (a dot on each), ticks of time as horizontal rules, the
//! step's label at the left and what it changed at the right; a step or an end marked
//! (a failure in red, a witness in green), an optional loop bracket, and a closing note
//! (a deadlock and why). Groups: `lifeline`, `step` (`step failing`, `step reached` for a
//! marked one), `tick`, `loop`, `end`.

use crate::svg::{text_width, Anchor, Font, Paint, Svg};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mark {
    Plain,
    /// Where a property fails (red).
    Failing,
    /// Where a property is witnessed (green).
    Reached,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Step {
    /// As numbered in the run (1 for the first step).
    pub number: usize,
    pub label: String,
    /// The lifelines it synchronises.
    pub lifelines: Vec<usize>,
    /// What it changed, in the user's names.
    pub notes: Vec<String>,
    pub mark: Mark,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Row {
    Step(Step),
    /// Time passes: a rule across the chart.
    Tick {
        number: usize,
        label: String,
    },
}

/// The note at the end: what the run shows.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Note {
    pub title: String,
    pub lines: Vec<String>,
    pub mark: Mark,
    /// The lifelines the note is about (a deadlock's held activities): marked at the
    /// chart's end.
    pub lifelines: Vec<usize>,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Chart {
    pub title: String,
    pub lifelines: Vec<String>,
    pub rows: Vec<Row>,
    /// The row where a lasso's loop starts (it runs to the last row).
    pub loop_from: Option<usize>,
    pub end: Option<Note>,
    /// Participants that take no part in the run, named under the title instead of
    /// drawn as lifelines.
    pub idle: Vec<String>,
}

const FONT: f64 = 11.0;
const MARGIN: f64 = 16.0;
const HEAD: f64 = 28.0;
const STEP: f64 = 24.0;
const TICK: f64 = 16.0;
const BAR: f64 = 10.0;
const LINE: f64 = 15.0;
const LOOP: f64 = 26.0;

fn colour(mark: Mark) -> &'static str {
    match mark {
        Mark::Plain => "#4e79a7",
        Mark::Failing => "#c0392b",
        Mark::Reached => "#2e8b57",
    }
}

/// The chart as an SVG document.
pub fn to_svg(chart: &Chart) -> String {
    let labels = chart
        .rows
        .iter()
        .map(|r| match r {
            Row::Step(s) => text_width(&format!("{}  {}", s.number, s.label), FONT),
            Row::Tick { label, .. } => text_width(label, FONT),
        })
        .fold(60.0, f64::max);
    let left = MARGIN + if chart.loop_from.is_some() { LOOP } else { 0.0 };
    let lanes_at = left + labels + 16.0;
    let lane_widths: Vec<f64> = chart
        .lifelines
        .iter()
        .map(|name| (text_width(name, FONT) * 1.1 + 16.0).max(70.0))
        .collect();
    let mut centres = Vec::new();
    let mut x = lanes_at;
    for w in &lane_widths {
        centres.push(x + w / 2.0);
        x += w + 8.0;
    }
    let lanes_end = x;
    let notes_end = chart
        .rows
        .iter()
        .filter_map(|r| match r {
            Row::Step(s) => {
                Some(notes_x(s, &centres, lanes_at) + text_width(&s.notes.join(", "), FONT))
            }
            Row::Tick { .. } => None,
        })
        .fold(lanes_end, f64::max);
    let idle =
        (!chart.idle.is_empty()).then(|| format!("taking no part: {}", chart.idle.join(", ")));
    let top = MARGIN + 26.0 + if idle.is_some() { LINE } else { 0.0 };
    let body_top = top + HEAD + 10.0;
    let mut y = body_top;
    let row_tops: Vec<f64> = chart
        .rows
        .iter()
        .map(|r| {
            let at = y;
            y += match r {
                Row::Step(_) => STEP,
                Row::Tick { .. } => TICK,
            };
            at
        })
        .collect();
    let marked = chart.end.as_ref().is_some_and(|n| !n.lifelines.is_empty());
    let body_bottom = y + 6.0 + if marked { STEP } else { 0.0 };
    let end_lines = chart.end.as_ref().map_or(0, |n| n.lines.len() + 1);
    let end_height = if end_lines > 0 {
        LINE * end_lines as f64 + 12.0
    } else {
        0.0
    };
    let end_width = chart.end.as_ref().map_or(0.0, |n| {
        std::iter::once(&n.title)
            .chain(&n.lines)
            .map(|l| text_width(l, FONT))
            .fold(0.0, f64::max)
            + 20.0
    });
    let width = notes_end
        .max(left + end_width)
        .max(MARGIN + text_width(&chart.title, 14.0))
        .max(MARGIN + idle.as_deref().map_or(0.0, |t| text_width(t, FONT)))
        + MARGIN;
    let height = body_bottom
        + if end_height > 0.0 {
            end_height + 14.0
        } else {
            0.0
        }
        + MARGIN;

    let mut svg = Svg::new();
    svg.text(MARGIN, MARGIN + 10.0, &chart.title, Font::new(14.0).bold());
    if let Some(idle) = &idle {
        svg.text(
            MARGIN,
            MARGIN + 10.0 + LINE + 2.0,
            idle,
            Font::new(FONT).italic().colour("#666666"),
        );
    }
    for (k, name) in chart.lifelines.iter().enumerate() {
        let c = centres[k];
        let w = lane_widths[k];
        svg.open("lifeline", Some(name));
        svg.rect(
            c - w / 2.0,
            top,
            w,
            HEAD,
            4.0,
            Paint::filled("#f3f3f3", "#666666"),
        );
        svg.text(
            c,
            top + 18.0,
            name,
            Font::new(FONT).bold().anchor(Anchor::Middle),
        );
        svg.line(
            c,
            top + HEAD,
            c,
            body_bottom,
            Paint::stroke("#999999").dash("4 3"),
        );
        svg.close();
    }
    let right = centres
        .last()
        .map_or(lanes_at, |&c| c + lane_widths[lane_widths.len() - 1] / 2.0);
    for (row, &at) in chart.rows.iter().zip(&row_tops) {
        match row {
            Row::Tick { number, label } => {
                svg.open("tick", Some(&format!("step {number}: {label}")));
                let mid = at + TICK / 2.0;
                svg.line(lanes_at - 4.0, mid, right, mid, Paint::stroke("#b0b0b0"));
                svg.text(
                    lanes_at - 12.0,
                    mid + 3.5,
                    label,
                    Font::new(FONT - 1.0).colour("#888888").anchor(Anchor::End),
                );
                svg.close();
            }
            Row::Step(step) => draw_step(&mut svg, step, at, &centres, lanes_at, lanes_end),
        }
    }
    if let Some(from) = chart.loop_from.filter(|&k| k < row_tops.len()) {
        svg.open("loop", Some("the run repeats from here"));
        let x = MARGIN + 8.0;
        let y0 = row_tops[from] + 2.0;
        let y1 = body_bottom - 8.0;
        let d = format!("M{},{} h-6 V{} h6", x + 8.0, y0, y1);
        svg.path(&d, Paint::stroke("#7b3294").width(1.5), None);
        svg.text(
            x - 4.0,
            y0 - 3.0,
            "loop",
            Font::new(FONT - 1.0).colour("#7b3294"),
        );
        svg.close();
    }
    if let Some(note) = &chart.end {
        let at = body_bottom + 8.0;
        let c = colour(note.mark);
        svg.open("end", Some(&note.title));
        for &k in &note.lifelines {
            if let Some(&x) = centres.get(k) {
                let y = body_bottom - STEP / 2.0 - 4.0;
                let d = format!(
                    "M{},{} l8,8 M{},{} l-8,8",
                    x - 4.0,
                    y - 4.0,
                    x + 4.0,
                    y - 4.0
                );
                svg.path(&d, Paint::stroke(c).width(2.5), None);
                svg.text(
                    x + 8.0,
                    y + 4.0,
                    "held",
                    Font::new(FONT - 1.0).bold().colour(c),
                );
            }
        }
        let fill = match note.mark {
            Mark::Failing => "#fdecea",
            Mark::Reached => "#eaf7ef",
            Mark::Plain => "#f3f3f3",
        };
        svg.rect(
            left,
            at,
            end_width.max(right - left),
            end_height,
            4.0,
            Paint::filled(fill, c),
        );
        svg.text(
            left + 10.0,
            at + LINE,
            &note.title,
            Font::new(FONT).bold().colour(c),
        );
        for (k, line) in note.lines.iter().enumerate() {
            // SVG collapses spaces: a line's indentation becomes its offset
            let text = line.trim_start();
            let indent = (line.len() - text.len()) as f64 * FONT * 0.5;
            svg.text(
                left + 10.0 + indent,
                at + LINE * (k as f64 + 2.0),
                text,
                Font::new(FONT),
            );
        }
        svg.close();
    }
    svg.finish(width, height, &chart.title)
}

/// Where a step's notes start: right of its bar.
fn notes_x(step: &Step, centres: &[f64], lanes_at: f64) -> f64 {
    step.lifelines
        .iter()
        .filter_map(|&k| centres.get(k).copied())
        .fold(lanes_at, f64::max)
        + 16.0
}

fn draw_step(svg: &mut Svg, step: &Step, at: f64, centres: &[f64], lanes_at: f64, lanes_end: f64) {
    let c = colour(step.mark);
    let class = match step.mark {
        Mark::Plain => "step",
        Mark::Failing => "step failing",
        Mark::Reached => "step reached",
    };
    svg.open(
        class,
        Some(&format!("step {}: {}", step.number, step.label)),
    );
    let mid = at + STEP / 2.0;
    if step.mark != Mark::Plain {
        svg.rect(
            MARGIN,
            at + 1.0,
            lanes_end - MARGIN,
            STEP - 2.0,
            3.0,
            Paint::filled(
                if step.mark == Mark::Failing {
                    "#fdecea"
                } else {
                    "#eaf7ef"
                },
                "none",
            ),
        );
    }
    let mut font = Font::new(FONT).anchor(Anchor::End);
    if step.mark != Mark::Plain {
        font = font.bold().colour(c);
    }
    svg.text(
        lanes_at - 12.0,
        mid + 4.0,
        &format!("{}  {}", step.number, step.label),
        font,
    );
    let xs: Vec<f64> = step
        .lifelines
        .iter()
        .filter_map(|&k| centres.get(k).copied())
        .collect();
    if let (Some(lo), Some(hi)) = (
        xs.iter().copied().reduce(f64::min),
        xs.iter().copied().reduce(f64::max),
    ) {
        svg.rect(
            lo - 8.0,
            mid - BAR / 2.0,
            hi - lo + 16.0,
            BAR,
            BAR / 2.0,
            Paint::filled(c, "none"),
        );
        for x in xs {
            svg.ellipse(x, mid, 3.0, 3.0, Paint::filled("#ffffff", c));
        }
    }
    if !step.notes.is_empty() {
        let text = step.notes.join(", ");
        let x = notes_x(step, centres, lanes_at);
        svg.rect(
            x - 2.0,
            mid - FONT / 2.0 - 2.0,
            text_width(&text, FONT) + 4.0,
            FONT + 4.0,
            2.0,
            Paint::filled("#ffffff", "none"),
        );
        svg.text(x, mid + 4.0, &text, Font::new(FONT).colour("#444444"));
    }
    svg.close();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_lifeline_step_tick_and_the_end_are_drawn() {
        let chart = Chart {
            title: "deadlock after 3 steps".into(),
            lifelines: vec!["ndd".into(), "sick".into(), "a<b".into()],
            rows: vec![
                Row::Step(Step {
                    number: 1,
                    label: "request ndd.GoTo".into(),
                    lifelines: vec![0],
                    notes: vec![],
                    mark: Mark::Plain,
                }),
                Row::Tick {
                    number: 2,
                    label: "tick".into(),
                },
                Row::Step(Step {
                    number: 3,
                    label: "sync".into(),
                    lifelines: vec![0, 2],
                    notes: vec!["x = 1".into(), "y = 2".into()],
                    mark: Mark::Failing,
                }),
            ],
            loop_from: Some(1),
            end: Some(Note {
                title: "deadlock".into(),
                lines: vec!["ndd.GoTo start held by navigate".into()],
                mark: Mark::Failing,
                lifelines: vec![0],
            }),
            idle: vec!["camera".into()],
        };
        let doc = to_svg(&chart);
        let classes = crate::xml::read::classes(&doc);
        let groups = |class: &str| classes.iter().filter(|c| *c == class).count();
        assert_eq!(groups("lifeline"), 3);
        assert_eq!(groups("step"), 1);
        assert_eq!(groups("step failing"), 1);
        assert_eq!(groups("tick"), 1);
        assert_eq!(groups("loop"), 1);
        assert_eq!(groups("end"), 1);
        let texts = crate::xml::read::texts(&doc);
        for want in [
            "a<b",
            "3  sync",
            "x = 1, y = 2",
            "ndd.GoTo start held by navigate",
            "loop",
        ] {
            assert!(texts.iter().any(|t| t == want), "{want}: {texts:?}");
        }
    }
}
