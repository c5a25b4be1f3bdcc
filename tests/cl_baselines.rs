//! The baselines' defining behaviour, each on a tiny problem with a
//! hand-computed answer: EWC's penalty gradient and Fisher, SI's path
//! integral, RWalk's normalised score, ER's loss, A-GEM's projection; and on
//! the toy learner's sequence that finetune forgets, `ours` and `wsn` do not,
//! EWC forgets less than finetune, and every method's run resumes exactly.

mod engine_common;
use candle_core::{backprop::GradStore, Device, Tensor, Var};
use engine_common::assert_metrics_json_complete;
use quadcl::cl::{
    diagonal_fisher, project, ErConfig, ErHooks, EwcConfig, EwcHooks, QuadraticPenalty, RwalkConfig, RwalkHooks,
    SiConfig, SiHooks,
};
use quadcl::headless::{run, RunOptions};
use quadcl::nn::Param;
use quadcl::nn::TaskId;
use quadcl::rl::{NoProbe, PolicyProbe};
use quadcl::rl::{OutputSample, UpdateHooks};
use rand::{Rng, SeedableRng};

fn param(name: &str, values: &[f32]) -> Param {
    let var = Var::from_tensor(&Tensor::new(values, &Device::Cpu).unwrap()).unwrap();
    Param::free(name, &var)
}

fn grad_of(loss: &Tensor, p: &Param) -> Vec<f32> {
    loss.backward().unwrap().get(p.var.as_tensor()).unwrap().to_vec1().unwrap()
}

#[test]
fn ewc_penalty_gradient_points_back_to_the_anchor_and_scales_with_the_fisher() {
    let p = param("actor.l0.weight", &[1.0, -2.0, 0.5]);
    let anchor = Tensor::new(&[0.0f32, 0.0, 0.5], &Device::Cpu).unwrap();
    let gradient = |fisher: [f32; 3]| {
        let mut penalty = QuadraticPenalty::default();
        penalty.accumulate(&p.name, Tensor::new(&fisher, &Device::Cpu).unwrap(), anchor.clone()).unwrap();
        grad_of(&penalty.loss(std::slice::from_ref(&p), 10.0).unwrap().unwrap(), &p)
    };
    let g = gradient([1.0, 1.0, 1.0]);
    // 2 lambda F (theta - theta*): a descent step moves theta towards the anchor.
    assert_eq!(g, [20.0, -40.0, 0.0]);
    let g2 = gradient([2.0, 0.5, 3.0]);
    assert_eq!(g2, [40.0, -20.0, 0.0]);
}

/// out = W x for a 2x2 W and stored inputs x_i.
struct Linear<'a> {
    w: &'a Param,
    xs: Vec<[f32; 2]>,
}

impl OutputSample for Linear<'_> {
    fn len(&self) -> usize {
        self.xs.len()
    }

    fn scaled_output(&self, i: usize) -> anyhow::Result<Tensor> {
        let x = Tensor::new(&self.xs[i], &Device::Cpu)?.reshape((2, 1))?;
        Ok(self.w.var.as_tensor().reshape((2, 2))?.matmul(&x)?.squeeze(1)?)
    }
}

#[test]
fn the_fisher_of_a_linear_output_is_the_mean_squared_input_and_skips_heads() {
    let w = param("actor.l0.weight", &[0.3, -0.2, 0.1, 0.7]);
    let head = param("actor.head.weight", &[1.0]);
    let sample = Linear { w: &w, xs: vec![[1.0, 2.0], [3.0, -1.0]] };
    let fisher = diagonal_fisher(&[w.clone(), head], &sample, 100).unwrap();
    // d out_k / d W[k][j] = x_j: F[k][j] = mean_i x_ij^2 = [5, 2.5] per row.
    assert_eq!(fisher["actor.l0.weight"].to_vec1::<f32>().unwrap(), [5.0, 2.5, 5.0, 2.5]);
    assert!(!fisher.contains_key("actor.head.weight"), "a task's own head is not regularised");
}

#[test]
fn si_omega_is_the_path_integral_of_the_task_gradient_on_a_quadratic() {
    // L = 0.5 sum a_i theta_i^2, plain gradient steps of 0.1.
    let a = [1.0f32, 4.0];
    let p = param("toy.l0.weight", &[1.0, -1.0]);
    let params = [p.clone()];
    let mut si = SiHooks::new(SiConfig { c: 1.0, xi: 0.1 });
    si.on_task_start(0, &params).unwrap();
    let mut theta = [1.0f32, -1.0];
    let mut omega = [0.0f32; 2];
    for _ in 0..3 {
        let coeff = Tensor::new(&a, &Device::Cpu).unwrap();
        let loss = p.var.as_tensor().sqr().unwrap().mul(&coeff).unwrap().sum_all().unwrap().affine(0.5, 0.0).unwrap();
        let mut grads: GradStore = loss.backward().unwrap();
        si.adjust_gradients(&params, &mut grads, &NoProbe).unwrap();
        let g: Vec<f32> = (0..2).map(|i| a[i] * theta[i]).collect();
        for i in 0..2 {
            let next = theta[i] - 0.1 * g[i];
            omega[i] += -g[i] * (next - theta[i]);
            theta[i] = next;
        }
        p.var.set(&Tensor::new(&theta, &Device::Cpu).unwrap()).unwrap();
        si.after_step(&params).unwrap();
    }
    let got: Vec<f32> = si.omega("toy.l0.weight").unwrap().to_vec1().unwrap();
    for i in 0..2 {
        assert!((got[i] - omega[i]).abs() < 1e-6, "omega {got:?}, by hand {omega:?}");
    }
    si.on_task_end(0, &params, &NoSample).unwrap();
    let importance: Vec<f32> = si.penalty().importance("toy.l0.weight").unwrap().to_vec1().unwrap();
    for i in 0..2 {
        let start = [1.0f32, -1.0][i];
        let want = (omega[i] / ((theta[i] - start).powi(2) + 0.1)).max(0.0);
        assert!((importance[i] - want).abs() < 1e-5, "Omega {importance:?}, want {want} at {i}");
    }
    assert_eq!(si.penalty().anchor("toy.l0.weight").unwrap().to_vec1::<f32>().unwrap(), theta);
}

// The toy's own weights: its losses are not the robot's, so the robot's tuned
// defaults (ER's beta 0.01, RWalk's lambda 0.1) do not carry over.
const TOY: &str =
    "seed = 2\niterations = 60\n[run]\nlearner = \"toy\"\n[method.ewc]\nlambda = 100.0\n[method.si]\nc = 1.0\n\
[method.er]\nbeta = 1.0\n[method.rwalk]\nlambda = 1.0\n[[task]]\nname = \"crash:FL\"\n[[task]]\nname = \"invert:RR\"\n";

fn toy_run(method: &str, dir: &std::path::Path) -> quadcl::engine::MetricsFile {
    let cfg = dir.join("run.toml");
    std::fs::write(&cfg, TOY).unwrap();
    let options = RunOptions { method: Some(method.into()), ..Default::default() };
    run(&cfg, &dir.join(method), options).unwrap()
}

#[test]
fn finetune_forgets_on_the_toy_sequence_the_mask_methods_do_not_and_every_other_method_forgets_less() {
    let tmp = tempfile::tempdir().unwrap();
    let forgetting = |m: &str| toy_run(m, tmp.path()).summary.forgetting.unwrap();
    let (ours, finetune, ewc) = (forgetting("ours"), forgetting("finetune"), forgetting("ewc"));
    assert_eq!(ours, 0.0);
    for masked in ["wsn", "packnet", "piggyback"] {
        assert_eq!(forgetting(masked), 0.0, "{masked}: a finished task's weights are frozen");
    }
    assert!(finetune > 0.01, "finetune forgot only {finetune}");
    assert!(ewc < finetune, "ewc forgot {ewc}, finetune {finetune}");
    for method in ["si", "rwalk", "er", "agem"] {
        let f = forgetting(method);
        assert!(f < finetune / 3.0, "{method} forgot {f}, finetune {finetune}: it protects nothing");
    }
    let json = assert_metrics_json_complete(&tmp.path().join("ewc"));
    assert!(json["steps"][0].get("switches").is_none(), "a dense method's steps record no switches");
    let wsn = assert_metrics_json_complete(&tmp.path().join("wsn"));
    assert_eq!(wsn["steps"][1]["switches"]["lambda"], "per-layer", "wsn records the rules it ran with");
    assert_eq!((json["method"].as_str(), json["method_settings"]["lambda"].as_f64()), (Some("ewc"), Some(100.0)));
    assert!(json["curves"][1]["performance"].as_array().unwrap().len() == 60);
}

#[test]
fn a_dense_run_resumed_after_an_interruption_gives_the_same_metrics() {
    for method in ["finetune", "ewc", "si", "rwalk", "wsn", "er", "agem", "packnet", "piggyback"] {
        let tmp = tempfile::tempdir().unwrap();
        let whole = toy_run(method, tmp.path());
        let cfg = tmp.path().join("run.toml");
        let out = tmp.path().join("parts");
        let options =
            |resume, stop_after| RunOptions { resume, stop_after, method: Some(method.into()), ..Default::default() };
        run(&cfg, &out, options(false, Some(1))).unwrap();
        let resumed = run(&cfg, &out, options(true, None)).unwrap();
        assert_eq!(resumed.eval_matrix, whole.eval_matrix, "{method}");
        assert_eq!(resumed.summary, whole.summary, "{method}");
        // Without the same --method the stored run differs: an error, not a silent switch.
        let err = format!("{:#}", run(&cfg, &out, RunOptions { resume: true, ..Default::default() }).unwrap_err());
        assert!(err.contains(method) && err.contains("ours"), "{err}");
    }
}

#[test]
fn ewc_state_round_trips_through_its_tensors() {
    let p = param("actor.l0.weight", &[1.0, 2.0]);
    let mut ewc = EwcHooks::new(EwcConfig::default());
    let sample = Linear { w: &param("actor.l0.weight", &[1.0, 0.0, 0.0, 1.0]), xs: vec![[1.0, 1.0]] };
    ewc.on_task_end(0, std::slice::from_ref(sample.w), &sample).unwrap();
    let mut restored = EwcHooks::new(EwcConfig::default());
    restored.load_state(&ewc.state().unwrap()).unwrap();
    let (a, b) = (ewc.penalty(), restored.penalty());
    assert_eq!(
        a.importance(&p.name).unwrap().to_vec1::<f32>().unwrap(),
        b.importance(&p.name).unwrap().to_vec1::<f32>().unwrap()
    );
    assert_eq!(a.anchor(&p.name).unwrap().to_vec1::<f32>().unwrap(), [1.0, 0.0, 0.0, 1.0]);
}

/// No samples: for hooks whose task end does not probe the policy.
struct NoSample;

impl OutputSample for NoSample {
    fn len(&self) -> usize {
        0
    }

    fn scaled_output(&self, _: usize) -> anyhow::Result<Tensor> {
        anyhow::bail!("no samples")
    }
}

#[test]
fn rwalk_score_is_the_fisher_normalised_path_integral_and_its_importance_is_normalised() {
    // L = 0.5 sum a_i theta_i^2, plain gradient steps of 0.1; alpha 1 and a Fisher update
    // every step make F the last squared gradient.
    let a = [1.0f32, 4.0];
    let p = param("toy.l0.weight", &[1.0, -1.0]);
    let params = [p.clone()];
    let cfg = RwalkConfig { lambda: 1.0, alpha: 1.0, fisher_every: 1, eps: 1e-8 };
    let mut rwalk = RwalkHooks::new(cfg);
    rwalk.on_task_start(0, &params).unwrap();
    let mut theta = [1.0f32, -1.0];
    let mut s = [0.0f32; 2];
    for _ in 0..3 {
        let coeff = Tensor::new(&a, &Device::Cpu).unwrap();
        let loss = p.var.as_tensor().sqr().unwrap().mul(&coeff).unwrap().sum_all().unwrap().affine(0.5, 0.0).unwrap();
        let mut grads: GradStore = loss.backward().unwrap();
        rwalk.adjust_gradients(&params, &mut grads, &NoProbe).unwrap();
        for i in 0..2 {
            let g = a[i] * theta[i];
            let next = theta[i] - 0.1 * g;
            let delta = next - theta[i];
            s[i] += -g * delta / (0.5 * g * g * delta * delta + 1e-8);
            theta[i] = next;
        }
        p.var.set(&Tensor::new(&theta, &Device::Cpu).unwrap()).unwrap();
        rwalk.after_step(&params).unwrap();
    }
    let fisher: Vec<f32> = rwalk.fisher("toy.l0.weight").unwrap().to_vec1().unwrap();
    rwalk.on_task_end(0, &params, &NoSample).unwrap();
    let importance: Vec<f32> = rwalk.penalty().importance("toy.l0.weight").unwrap().to_vec1().unwrap();
    let (f_max, s_max) = (fisher[0].max(fisher[1]), s[0].max(s[1]));
    for i in 0..2 {
        let want = fisher[i] / f_max + s[i].max(0.0) / s_max;
        assert!(
            (importance[i] - want).abs() < 1e-4 * want.abs().max(1.0),
            "importance {importance:?} at {i}, want {want}"
        );
    }
    // A second task averages its normalised score with the first's and replaces the importance.
    let mut restored = RwalkHooks::new(RwalkConfig::default());
    restored.load_state(&rwalk.state().unwrap()).unwrap();
    assert_eq!(
        restored.penalty().importance("toy.l0.weight").unwrap().to_vec1::<f32>().unwrap(),
        importance,
        "the state round-trips"
    );
}

/// out = W x for one 2x2 W shared by every task (a probe of the `Linear` sample's network).
struct LinearProbe<'a> {
    w: &'a Param,
}

impl PolicyProbe for LinearProbe<'_> {
    fn outputs(&self, _task: TaskId, inputs: &[f32], rows: usize) -> anyhow::Result<Tensor> {
        let x = Tensor::from_slice(inputs, (rows, 2), &Device::Cpu)?;
        Ok(x.matmul(&self.w.var.as_tensor().reshape((2, 2))?.t()?)?)
    }
}

/// The `Linear` sample with rehearsal rows (sigma 0.5).
struct Rehearsal<'a>(Linear<'a>);

impl OutputSample for Rehearsal<'_> {
    fn len(&self) -> usize {
        self.0.len()
    }

    fn scaled_output(&self, i: usize) -> anyhow::Result<Tensor> {
        self.0.scaled_output(i)
    }

    fn replay_row(&self, i: usize) -> anyhow::Result<(Vec<f32>, Vec<f32>)> {
        Ok((self.0.xs[i].to_vec(), self.0.scaled_output(i)?.to_vec1()?))
    }

    fn sigma(&self) -> anyhow::Result<Vec<f32>> {
        Ok(vec![0.5, 0.5])
    }
}

#[test]
fn er_loss_is_zero_when_the_policy_equals_the_stored_one_and_grows_as_it_moves() {
    let w = param("actor.l0.weight", &[0.3, -0.2, 0.1, 0.7]);
    let rows = [[1.0f32, 2.0], [3.0, -1.0], [0.5, 0.5]];
    let sample = Rehearsal(Linear { w: &w, xs: rows.to_vec() });
    let mut er = ErHooks::new(ErConfig { beta: 2.0, buffer_size: 10, batch_size: 6 });
    er.on_task_end(0, std::slice::from_ref(&w), &sample).unwrap();
    er.on_task_start(1, std::slice::from_ref(&w)).unwrap();
    let probe = LinearProbe { w: &w };
    let mut loss = || {
        let (loss, metrics) = er.extra_loss(std::slice::from_ref(&w), &probe).unwrap().unwrap();
        (f64::from(loss.to_scalar::<f32>().unwrap()), metrics["losses/er_clone_kl"])
    };
    assert_eq!(loss(), (0.0, 0.0));
    // W + 0.1 everywhere moves both outputs of a row by 0.1 (x0 + x1): KL = 2 d^2 / (2 * 0.25).
    w.var.set(&Tensor::new(&[0.4f32, -0.1, 0.2, 0.8], &Device::Cpu).unwrap()).unwrap();
    let (weighted, kl) = loss();
    assert!(kl > 0.0 && (weighted - 2.0 * kl).abs() < 1e-5, "beta * KL: {weighted} vs {kl}");
    let max_kl = rows.iter().map(|x| f64::from(2.0 * (0.1 * (x[0] + x[1])).powi(2) / 0.5)).fold(0.0, f64::max);
    assert!(kl <= max_kl + 1e-6, "KL {kl} above the largest row's {max_kl}");
}

#[test]
fn agem_projection_never_leaves_a_negative_dot_product_with_the_reference() {
    let p = [param("toy.l0.weight", &[0.0; 5]), param("toy.l0.bias", &[0.0; 3])];
    // A GradStore of random gradients for both parameters, through a linear loss.
    let store = |rng: &mut rand_chacha::ChaCha8Rng| -> GradStore {
        let mut loss = Tensor::new(0f32, &Device::Cpu).unwrap();
        for (q, n) in p.iter().zip([5usize, 3]) {
            let c: Vec<f32> = (0..n).map(|_| rng.gen_range(-1.0f32..1.0)).collect();
            let c = Tensor::new(c.as_slice(), &Device::Cpu).unwrap();
            loss = loss.add(&q.var.as_tensor().mul(&c).unwrap().sum_all().unwrap()).unwrap();
        }
        loss.backward().unwrap()
    };
    let values = |g: &GradStore| -> Vec<f32> {
        p.iter().flat_map(|q| g.get(q.var.as_tensor()).unwrap().to_vec1::<f32>().unwrap()).collect()
    };
    let dot = |a: &[f32], b: &[f32]| -> f32 { a.iter().zip(b).map(|(x, y)| x * y).sum() };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut projected = 0;
    for _ in 0..200 {
        let (mut g, reference) = (store(&mut rng), store(&mut rng));
        let (before, r) = (values(&g), values(&reference));
        let did = project(&p, &mut g, &reference).unwrap();
        let after = values(&g);
        assert!(dot(&after, &r) >= -1e-5, "projected g . g_ref = {}", dot(&after, &r));
        assert_eq!(did, dot(&before, &r) < 0.0);
        if did {
            projected += 1;
            assert!(dot(&after, &r).abs() < 1e-5, "a projection lands on the boundary");
        } else {
            assert_eq!(after, before, "an agreeing gradient is left alone");
        }
    }
    assert!(projected > 50, "only {projected} of 200 random pairs disagreed");
}

#[test]
fn piggybacks_settings_in_metrics_json_are_the_ones_its_networks_trained_with() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("run.toml");
    std::fs::write(&cfg, format!("{TOY}[method.piggyback]\nlr = 3e-4\nthreshold = 4e-3\n")).unwrap();
    let options = RunOptions { method: Some("piggyback".into()), ..Default::default() };
    let out = tmp.path().join("piggyback");
    run(&cfg, &out, options).unwrap();
    let json = assert_metrics_json_complete(&out);
    assert_eq!(json["method_settings"]["lr"].as_f64(), Some(3e-4));
    assert_eq!(json["method_settings"]["threshold"].as_f64(), Some(4e-3));
    // The checkpoint records each network's mask configuration as it trained.
    let manifest = out.join("checkpoints/step-01-invert_RR/manifest.json");
    let manifest: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&manifest).unwrap()).unwrap();
    let networks = manifest["networks"].as_array().unwrap();
    assert!(!networks.is_empty());
    for net in networks {
        let mask = &net["mask"];
        assert_eq!((mask["rule"].as_str(), mask["piggyback_learning_rate"].as_f64()), (Some("piggyback"), Some(3e-4)));
        assert_eq!(mask["piggyback_threshold"].as_f64(), Some(4e-3), "{}", net["name"]);
    }
}

#[test]
fn every_methods_key_setting_in_metrics_json_is_the_one_it_trained_with() {
    // (method, the run file's table, its key, two values): each value is written into
    // metrics.json as given, and the two values train differently, so the written value
    // is the one the update used (a setting recorded but not applied trains alike).
    let cases: [(&str, &str, &str, f64, f64); 7] = [
        ("ewc", "[method.ewc]", "lambda", 100.0, 3000.0),
        ("si", "[method.si]", "c", 0.3, 30.0),
        ("rwalk", "[method.rwalk]", "lambda", 0.1, 10.0),
        ("er", "[method.er]", "beta", 0.01, 10.0),
        ("agem", "[method.agem]", "buffer_size", 8.0, 64.0),
        ("packnet", "[method.packnet]", "keep", 0.25, 0.75),
        ("wsn", "[method]", "capacity", 0.2, 0.6),
    ];
    let tasks = "[[task]]\nname = \"crash:FL\"\n[[task]]\nname = \"invert:RR\"\n";
    let tmp = tempfile::tempdir().unwrap();
    for (method, table, key, a, b) in cases {
        let run_with = |value: f64| {
            let dir = tmp.path().join(format!("{method}-{value}"));
            std::fs::create_dir_all(&dir).unwrap();
            let cfg = dir.join("run.toml");
            let value_text = if key == "buffer_size" { format!("{}", value as usize) } else { format!("{value:?}") };
            let own_table = if table == "[method]" { String::new() } else { format!("{table}\n") };
            let text = format!(
                "seed = 2\niterations = 60\n[run]\nlearner = \"toy\"\n[method]\nname = \"{method}\"\n\
                 {own_table}{key} = {value_text}\n{tasks}"
            );
            std::fs::write(&cfg, &text).unwrap();
            let m = run(&cfg, &dir.join("out"), RunOptions::default()).unwrap();
            assert_eq!(m.method, method, "{text}");
            (assert_metrics_json_complete(&dir.join("out")), m.eval_matrix)
        };
        let ((json_a, matrix_a), (json_b, matrix_b)) = (run_with(a), run_with(b));
        for (json, value) in [(&json_a, a), (&json_b, b)] {
            let written = if table == "[method]" {
                // WSN's capacity is a switch: each step records the switches it trained with.
                let steps = json["steps"].as_array().unwrap();
                assert_eq!(steps.len(), 2, "{method}");
                for s in steps {
                    assert_eq!(s["switches"][key].as_f64(), Some(value), "{method}: step {}", s["step"]);
                }
                steps[0]["switches"][key].as_f64()
            } else {
                json["method_settings"][key].as_f64()
            };
            assert_eq!(written, Some(value), "{method} {key}");
        }
        assert_ne!(
            matrix_a, matrix_b,
            "{method}: {key} {a} and {b} trained alike, so the setting never reached training"
        );
    }
}
