//! "What is wrong" on the bundled demo campaign: its hidden effect
//! (thermal_clearance, examples/demo_campaign/README.md) must show as
//! residual structure in temperature (and viscosity), found at the level of
//! pumps with Holm-adjusted p-values.

use gearpump::campaign::run::{run_campaign, CampaignOptions, DesignSource, Silent};
use gearpump::diagnosis::findings::{findings, rows_from_campaign};
use std::path::Path;

#[test]
fn the_demo_campaigns_hidden_thermal_effect_shows_in_temperature() {
    let source = DesignSource::load(None, &[]).unwrap();
    let out = std::env::temp_dir().join(format!("gearpump-findings-{}", std::process::id()));
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/demo_campaign/campaign.csv");
    let result = run_campaign(&source, &data, &out, CampaignOptions::default(), &Silent).unwrap();
    let rows = rows_from_campaign(&result, &source.design.oil);
    assert_eq!(rows.len(), 280);
    let f = findings(&rows);
    for x in &f {
        println!(
            "{:<26} {:<8} effect {:+.4} t {:+8.2} p_adj {:.2e}",
            x.feature, x.kind, x.effect, x.statistic, x.p_adjusted
        );
    }
    let get = |n: &str| f.iter().find(|x| x.feature == n).unwrap();
    // clearances open with temperature: the model over-predicts eta_v more when hot
    assert!(get("temp_c").p_adjusted < 1e-3 && get("temp_c").effect < 0.0);
    assert!(get("viscosity").p_adjusted < 1e-3 && get("viscosity").effect > 0.0);
    // the measured clearances themselves are used correctly (trace-driven)
    for c in ["tip_clearance_drive_um", "tip_clearance_driven_um"] {
        assert!(get(c).p_adjusted > 0.01, "{c}: {:?}", get(c));
    }
    let _ = std::fs::remove_dir_all(&out);
}
