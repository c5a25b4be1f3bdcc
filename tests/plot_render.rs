//! The figures of `quadcl plot` from the committed fixture `tests/plot_fixture/two-tasks/`
//! (a `metrics.json` of two steps whose curves carry a `plasticity` object): each renders to
//! a PNG of its size and to an SVG whose text holds the figure's title, the runs' names, the
//! tasks and the axes' units; the command line writes them and names bad input.

use quadcl::plot::{load_run, render_png, write_figures, Figure, PlotOptions, RunData};
use std::path::{Path, PathBuf};
use std::process::Command;

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/plot_fixture/two-tasks")
}

/// The fixture under its folder's name and again as "baseline".
fn two_runs() -> Vec<RunData> {
    vec![load_run(&fixture(), None).unwrap(), load_run(&fixture().join("metrics.json"), Some("baseline")).unwrap()]
}

/// The text of every `<text>` element of an SVG document, unescaped.
fn svg_texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| Some(t.split_once('>')?.1.split_once("</text>")?.0))
        .map(|t| unescape(t.trim()))
        .collect()
}

fn unescape(s: &str) -> String {
    s.replace("&lt;", "<").replace("&gt;", ">").replace("&quot;", "\"").replace("&apos;", "'").replace("&amp;", "&")
}

/// The PNG's width and height, and how many distinct colours its pixels have.
fn png_facts(path: &Path) -> (u32, u32, usize) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut pixels).unwrap();
    let colours: std::collections::BTreeSet<&[u8]> = pixels[..info.buffer_size()].chunks(3).collect();
    (info.width, info.height, colours.len())
}

fn assert_has(texts: &[String], wanted: &[&str], file: &str) {
    for w in wanted {
        assert!(texts.iter().any(|t| t == w), "{file}: no text {w:?} in {texts:?}");
    }
}

#[test]
fn every_figure_renders_to_png_and_svg_with_its_title_runs_tasks_and_units() {
    let runs = two_runs();
    let out = tempfile::tempdir().unwrap();
    let files = write_figures(&runs, out.path(), &PlotOptions::default()).unwrap();
    let names: Vec<String> = files.iter().map(|f| f.file_name().unwrap().to_string_lossy().into_owned()).collect();
    let stems = ["task_curves", "sequence", "eval_matrix", "plasticity"];
    let expected: Vec<String> = stems.iter().flat_map(|s| [format!("{s}.png"), format!("{s}.svg")]).collect();
    assert_eq!(names, expected);
    for (figure, stem) in Figure::ALL.into_iter().zip(stems) {
        let (w, h, colours) = png_facts(&out.path().join(format!("{stem}.png")));
        assert_eq!((w, h), figure.size(&runs), "{stem}.png");
        assert!(colours > 20, "{stem}.png has {colours} colours: nothing drawn?");
        let svg = std::fs::read_to_string(out.path().join(format!("{stem}.svg"))).unwrap();
        assert!(svg.contains(&format!("width=\"{w}\"")) && svg.contains(&format!("height=\"{h}\"")), "{stem}.svg size");
    }
    let texts = |stem: &str| svg_texts(&std::fs::read_to_string(out.path().join(format!("{stem}.svg"))).unwrap());
    assert_has(
        &texts("task_curves"),
        &[
            "Training curves per task",
            "two-tasks",
            "baseline",
            "1. crash:FL: performance",
            "2. invert:RL: yaw rate error",
            "normalised return (0-1)",
            "|v_xy - v_cmd| (m/s)",
            "|ω_z - ω_cmd| (rad/s)",
            "iteration of the task",
        ],
        "task_curves.svg",
    );
    assert_has(
        &texts("sequence"),
        &["The whole sequence", "two-tasks", "baseline", "crash:FL", "invert:RL", "iteration of the sequence"],
        "sequence.svg",
    );
    assert_has(
        &texts("eval_matrix"),
        &[
            "Evaluation matrix and forgetting",
            "two-tasks",
            "baseline",
            "average performance 0.521, forgetting 0.000",
            "after 1: crash:FL",
            "after 2: invert:RL",
            "none",
            "0.892",
            "0.633",
            "forgetting",
            "+0.000",
        ],
        "eval_matrix.svg",
    );
    assert_has(
        &texts("plasticity"),
        &[
            "Plasticity measures, each run's mean over its networks or layers",
            "two-tasks",
            "baseline",
            "dormant units (ReDo: mean |activation| <= 0.1 of the layer's mean)",
            "effective rank of the last hidden layer's features",
            "share of the task's selected weights it may still change",
        ],
        "plasticity.svg",
    );
}

#[test]
fn one_runs_plasticity_figure_names_each_network_and_layer() {
    let run = load_run(&fixture(), None).unwrap();
    let svg = quadcl::plot::render_svg(Figure::Plasticity, &[run], &PlotOptions { smooth: 3 }).unwrap();
    assert_has(
        &svg_texts(&svg),
        &[
            "Plasticity measures: two-tasks (moving mean over 3 iterations)",
            "actor",
            "critic",
            "actor.l0",
            "actor.l1",
            "mean |w| (weight units)",
        ],
        "plasticity.svg",
    );
}

#[test]
fn a_figure_is_the_same_bytes_every_time() {
    let runs = two_runs();
    let first = render_png(Figure::TaskCurves, &runs, &PlotOptions::default()).unwrap();
    assert_eq!(first, render_png(Figure::TaskCurves, &runs, &PlotOptions::default()).unwrap());
    assert_ne!(first, render_png(Figure::TaskCurves, &runs, &PlotOptions { smooth: 4 }).unwrap());
}

fn quadcl(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_quadcl")).args(args).output().unwrap()
}

#[test]
fn the_plot_command_writes_the_figures_and_names_bad_input() {
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("figures");
    let fixture = fixture();
    let ok = quadcl(&["plot", fixture.to_str().unwrap(), "--out", dir.to_str().unwrap(), "--label", "mine"]);
    assert!(ok.status.success(), "{}", String::from_utf8_lossy(&ok.stderr));
    let printed = String::from_utf8_lossy(&ok.stdout);
    assert_eq!(printed.lines().count(), 8, "{printed}");
    let svg = std::fs::read_to_string(dir.join("sequence.svg")).unwrap();
    assert_has(&svg_texts(&svg), &["mine"], "sequence.svg");

    let empty = out.path().join("not-a-run");
    std::fs::create_dir(&empty).unwrap();
    let err = quadcl(&["plot", empty.to_str().unwrap(), "--out", dir.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&err.stderr);
    assert!(!err.status.success() && stderr.contains("not-a-run: no metrics.json"), "{stderr}");

    let two_labels = quadcl(&["plot", fixture.to_str().unwrap(), "--out", "x", "--label", "a", "--label", "b"]);
    let stderr = String::from_utf8_lossy(&two_labels.stderr);
    assert!(!two_labels.status.success() && stderr.contains("2 --label for 1 runs"), "{stderr}");
}
