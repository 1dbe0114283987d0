//! What a diagnosis found ([`Diagnosis`]) and where it is written: below
//! both the decision (`diagnose`) and the report (`report`), which each
//! name it.

use std::path::PathBuf;

use serde_json::Value;

use super::candidates::CandidateScore;
use super::findings::Finding;

/// File names written into the output folder (besides the campaign's).
pub const DIAGNOSIS_JSON: &str = "diagnosis.json";
pub const EXTENDED_DIR: &str = "extended";
/// The extended model as a design file (`gearpump_campaign::extend`).
pub const EXTENDED_DESIGN: &str = "extended_design.toml";

/// What a diagnosis found (the full record is `json`).
#[derive(Debug, Clone)]
pub struct Diagnosis {
    /// The first cause (`causes[0]`).
    pub cause: Option<&'static str>,
    /// Every cause selected, in order.
    pub causes: Vec<&'static str>,
    /// Material structure remains (docs/diagnosis.md, "Decision rule").
    pub unexplained: bool,
    pub ambiguous_with: Vec<&'static str>,
    /// Pumps whose residual stands apart from the population (in the
    /// analysis of every pump); the verdict is the analysis without them.
    pub out_of_family: Vec<String>,
    pub baseline_rmse: f64,
    /// RMSE of the extended model (the cause, or the partial candidate)
    /// over every test, the out-of-family pumps' too (the verdict's ratio,
    /// over the tests analysed, is `json["gain"]["rmse_ratio"]`).
    pub extended_rmse: Option<f64>,
    pub findings: Vec<Finding>,
    pub candidates: Vec<CandidateScore>,
    /// Model runs of the candidate stage.
    pub runs: usize,
    pub json: Value,
    pub files: Vec<PathBuf>,
}

#[cfg(test)]
mod tests {
    /// Every file a diagnosis writes is one the output folder's staging
    /// treats as a result (`gearpump_campaign::io`), so a later campaign
    /// into the folder does not leave it looking current.
    #[test]
    fn every_diagnosis_file_is_a_result_name() {
        for name in [
            crate::verdict::DIAGNOSIS_JSON,
            crate::verdict::EXTENDED_DIR,
            crate::verdict::EXTENDED_DESIGN,
            crate::report::DIAGNOSIS_SVG,
            crate::report::FEATURES_SVG,
            gearpump_campaign::run::REPORT_MD,
        ]
        .into_iter()
        .chain(gearpump_campaign::plots::FIGURE_FILES)
        {
            assert!(
                gearpump_campaign::io::RESULT_NAMES.contains(&name),
                "{name}"
            );
        }
    }
}
