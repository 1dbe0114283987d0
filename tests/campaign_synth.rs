//! Self-consistency of `synth` and `campaign`: a noise-free synthetic
//! campaign with no hidden effect is reproduced by the trace-driven campaign
//! (d = 0, delta_nu = 0 at every condition), and with the rig's 0.5 % flow
//! noise every mean residual stays within the spread the noise explains.

mod campaign_common;

use campaign_common::*;
use gearpump::campaign::run::{run_campaign, CampaignOptions, DesignSource, Silent};
use gearpump::campaign::synth::{synthesize_with, Noise, SynthOptions};
use gearpump::campaign::{write_campaign_csv, Condition};

fn conditions(list: &[(f64, f64, f64)]) -> Vec<Condition> {
    list.iter()
        .map(|&(pressure_bar, speed_rpm, temp_c)| Condition {
            pressure_bar,
            speed_rpm,
            temp_c,
        })
        .collect()
}

#[test]
fn campaign_synth_noise_free_without_effect_gives_zero_residuals() {
    let s = Scratch::new("synth-zero");
    // All 14 conditions of Table 2, micromotion on (the defaults), 2 samples.
    let opts = SynthOptions {
        samples: 2,
        noise: Noise::NONE,
        jobs: Some(2),
        ..SynthOptions::paper(11)
    };
    let syn = synthesize_with(pump(), &opts, &Silent).unwrap();
    assert_eq!(syn.records.len(), 28);
    let data = s.path("c.csv");
    write_campaign_csv(&data, &syn.records).unwrap();
    let source = DesignSource::load(None, &[]).unwrap();
    let out = s.path("out");
    let result = run_campaign(
        &source,
        &data,
        &out,
        CampaignOptions {
            jobs: Some(2),
            micromotion: true,
        },
        &Silent,
    )
    .unwrap();
    assert_eq!(result.summaries.len(), 14);
    assert!(result.failed.is_empty());
    for o in &result.outcomes {
        assert!(o.d.abs() < 1e-9, "d = {}", o.d);
    }
    for c in &result.summaries {
        let st = &c.stats;
        assert_eq!(st.n_samples, 2);
        assert!(st.d_mean.unwrap().abs() < 1e-9, "{}: {st:?}", c.condition);
        assert!(st.delta_nu.unwrap() < 1e-9, "{}: {st:?}", c.condition);
    }
}

#[test]
fn campaign_synth_rig_noise_stays_within_the_expected_spread() {
    let s = Scratch::new("synth-noise");
    let opts = SynthOptions {
        samples: 10,
        noise: Noise::RIG,
        conditions: conditions(&[
            (10.0, 1000.0, 60.0),
            (40.0, 1000.0, 60.0),
            (30.0, 500.0, 120.0),
            (30.0, 2000.0, 120.0),
        ]),
        jobs: Some(2),
        ..SynthOptions::paper(2020)
    };
    let syn = synthesize_with(pump(), &opts, &Silent).unwrap();
    // The noise is what was asked for: relative flow errors with sd 0.005.
    let rel: Vec<f64> = syn
        .records
        .iter()
        .zip(&syn.true_flow_lpm)
        .map(|(r, q)| r.flow_lpm / q - 1.0)
        .collect();
    let sd = (rel.iter().map(|x| x * x).sum::<f64>() / rel.len() as f64).sqrt();
    assert!(sd > 0.003 && sd < 0.007, "flow noise sd {sd}");

    let data = s.path("c.csv");
    write_campaign_csv(&data, &syn.records).unwrap();
    let source = DesignSource::load(None, &[]).unwrap();
    let result = run_campaign(
        &source,
        &data,
        &s.path("out"),
        CampaignOptions {
            jobs: Some(2),
            micromotion: true,
        },
        &Silent,
    )
    .unwrap();
    let mut covering = 0;
    for c in &result.summaries {
        let st = &c.stats;
        let n = st.n_samples as f64;
        assert_eq!(n, 10.0);
        // sd of d from the flow noise alone: 0.005 eta_v
        let eta: f64 = result
            .campaign
            .rows
            .iter()
            .zip(&result.outcomes)
            .filter(|(r, _)| r.condition == c.condition)
            .map(|(_, o)| o.eta_v_sim)
            .sum::<f64>()
            / n;
        let sigma = 0.005 * eta;
        let (m, sd) = (st.d_mean.unwrap(), st.d_std.unwrap());
        assert!(
            m.abs() < 4.0 * sigma / n.sqrt(),
            "{}: d_mean {m}, sigma {sigma}",
            c.condition
        );
        // S_d^2 / sigma^2 ~ chi2(9)/9: within [0.16, 2.9] far beyond 99.9 %
        assert!(
            sd > 0.4 * sigma && sd < 1.7 * sigma,
            "{}: S_d {sd}, sigma {sigma}",
            c.condition
        );
        let (lo, hi) = (st.ci_low.unwrap(), st.ci_high.unwrap());
        if lo <= 0.0 && hi >= 0.0 {
            covering += 1;
        }
        // the interval's half width is t S_d / sqrt(n), the spread of the mean
        assert!((hi - lo) / 2.0 < 2.262 * 1.7 * sigma / n.sqrt());
    }
    assert!(covering >= 3, "{covering} of 4 intervals contain 0");
}
