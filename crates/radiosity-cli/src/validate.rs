//! `radiosity validate cie171`: the electric-lighting test cases of CIE 171:2006
//! ([`radiosity_experiments::cie171`]) with, per case and point, the reference, the engine's
//! value and the deviation; per case the published validations' verdict (5 % at every point,
//! 10 % on average) and this project's target; `--csv` the table. A case that misses its
//! target makes the command fail, after everything is printed and written.

use crate::args::{ValidateArgs, ValidateSuite};
use anyhow::{bail, Result};
use radiosity_experiments::cie171::{
    self, Case, CaseResult, CIE_OVERALL_PERCENT, CIE_POINT_PERCENT,
};
use std::fmt::Write as _;
use std::io::Write as _;

/// Run the suite `a.suite`.
pub fn run(a: ValidateArgs) -> Result<()> {
    match a.suite {
        ValidateSuite::Cie171 => cie171_suite(&a),
    }
}

fn cie171_suite(a: &ValidateArgs) -> Result<()> {
    let cases = match &a.case {
        Some(id) => match Case::from_id(id) {
            Some(c) => vec![c],
            None => {
                let ids: Vec<&str> = Case::ALL.iter().map(|c| c.id()).collect();
                bail!("--case {id}: unknown case (possible: {})", ids.join(", "))
            }
        },
        None => Case::ALL.to_vec(),
    };
    if let Some(p) = &a.csv {
        crate::settings::check_output(p)?;
    }
    let mut results = Vec::new();
    for case in cases {
        let r = cie171::run(case)?;
        print!("{}", table(&r));
        let _ = std::io::stdout().flush();
        results.push(r);
    }
    if results.len() > 1 {
        print!("{}", summary(&results));
    }
    if let Some(p) = &a.csv {
        radiosity::export::write_text(p, &csv(&results))?;
        println!(
            "wrote {} ({} rows)",
            p.display(),
            results.iter().map(|r| r.rows.len()).sum::<usize>()
        );
    }
    let missed: Vec<String> = results
        .iter()
        .filter(|r| !r.target_pass())
        .map(|r| {
            format!(
                "{} (worst {:.3} %, target {} %)",
                r.case,
                r.worst_percent(),
                r.case.target_percent()
            )
        })
        .collect();
    if !missed.is_empty() {
        bail!(
            "CIE 171: missed this project's target: {}",
            missed.join("; ")
        );
    }
    Ok(())
}

fn pass(ok: bool) -> &'static str {
    if ok {
        "pass"
    } else {
        "FAIL"
    }
}

/// One case as text: its title, how the reference is computed, the settings that differ from
/// the pipeline's defaults, a row per point, and the verdicts.
fn table(r: &CaseResult) -> String {
    let case = r.case;
    let mut s = format!("CIE 171:2006 test case {case}: {}\n", case.title());
    let _ = writeln!(s, "  reference: {}", case.formula());
    if r.settings.is_empty() {
        let _ = writeln!(s, "  settings:  the lighting pipeline's defaults");
    }
    for line in &r.settings {
        let _ = writeln!(s, "  settings:  {line}");
    }
    let _ = writeln!(
        s,
        "  {:<14} {:>6} {:>6} {:>6} {:>14} {:>14} {:>10}",
        "point", "x", "y", "z", "reference", "ours", "deviation"
    );
    for row in &r.rows {
        let [x, y, z] = row.position;
        let _ = writeln!(
            s,
            "  {:<14} {x:>6.3} {y:>6.3} {z:>6.3} {:>11.4} {:<2} {:>11.4} {:<2} {:>+9.4} %",
            row.point, row.reference, row.unit, row.ours, row.unit, row.deviation_percent
        );
    }
    let _ = writeln!(
        s,
        "  {case}: worst {:.4} %, mean {:.4} % ({:.2} s); CIE criterion ({CIE_POINT_PERCENT} % every point, {CIE_OVERALL_PERCENT} % mean): {}; target ({} % every point): {}\n",
        r.worst_percent(),
        r.mean_percent(),
        r.seconds,
        pass(r.cie_pass()),
        case.target_percent(),
        pass(r.target_pass())
    );
    s
}

/// Every case on a line.
fn summary(results: &[CaseResult]) -> String {
    let mut s = format!(
        "{:<5} {:>6} {:>10} {:>10} {:>6} {:>8}\n",
        "case", "points", "worst %", "mean %", "CIE", "target"
    );
    for r in results {
        let _ = writeln!(
            s,
            "{:<5} {:>6} {:>10.4} {:>10.4} {:>6} {:>8}",
            r.case.id(),
            r.rows.len(),
            r.worst_percent(),
            r.mean_percent(),
            pass(r.cie_pass()),
            format!("{} ({} %)", pass(r.target_pass()), r.case.target_percent())
        );
    }
    s
}

/// The table as CSV: `case,point,x,y,z,reference,ours,deviation_percent`, each number in the
/// shortest form that reads back to the same value.
fn csv(results: &[CaseResult]) -> String {
    let mut s = String::from("case,point,x,y,z,reference,ours,deviation_percent\n");
    for r in results {
        for row in &r.rows {
            let [x, y, z] = row.position;
            let _ = writeln!(
                s,
                "{},{},{x},{y},{z},{},{},{}",
                r.case.id(),
                row.point,
                row.reference,
                row.ours,
                row.deviation_percent
            );
        }
    }
    s
}
