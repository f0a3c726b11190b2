//! `isotrack trim` and `isotrack replay`: the fixed-wing model on its own, for flight-dynamics
//! users who check it against their own data.

use crate::cli::{ReplayArgs, TrimArgs};
use crate::exit;
use crate::output::num;
use crate::run::Failure;
use isotrack_core::numtext::Echo;
use isotrack_vehicles::fixed_wing::dynamics::Deltas;
use isotrack_vehicles::fixed_wing::gains::compute_gains;
use isotrack_vehicles::fixed_wing::params::Aerosonde;
use isotrack_vehicles::fixed_wing::replay::{self, REPLAY_COLUMNS};
use isotrack_vehicles::fixed_wing::trim::{trim as solve_trim, trim_state};
use isotrack_vehicles::{FixedWing, FixedWingConfig};
use serde_json::json;
use std::io::Write;
use std::path::Path;

/// `isotrack trim`.
pub fn trim(a: &TrimArgs) -> Result<(), Failure> {
    let p = Aerosonde::beard_mclain_2012();
    let t = solve_trim(&p, a.airspeed_mps).map_err(|e| Failure {
        code: exit::USAGE,
        message: e.to_string(),
    })?;
    let g = compute_gains(&p, &t, a.ecen674_gains);
    if a.json {
        let j = json!({
            "airspeed_mps": t.airspeed_mps,
            "alpha_rad": t.alpha_rad,
            "theta_rad": t.alpha_rad,
            "delta_e_rad": t.delta_e_rad,
            "delta_a_rad": 0.0,
            "delta_r_rad": 0.0,
            "delta_t": t.delta_t,
            "u_mps": t.u_mps,
            "w_mps": t.w_mps,
            "gains": g,
        });
        out_data!("{}\n", serde_json::to_string_pretty(&j).unwrap_or_default());
    } else {
        outln!(
            "wings-level trim at {} m/s (gamma = 0, Aerosonde 2012 parameters)",
            t.airspeed_mps
        );
        outln!(
            "  alpha = theta = {:.7} rad   delta_e = {:.7} rad   delta_t = {:.6}",
            t.alpha_rad,
            t.delta_e_rad,
            t.delta_t
        );
        outln!(
            "  u = {:.5} m/s   w = {:.5} m/s   delta_a = delta_r = 0",
            t.u_mps,
            t.w_mps
        );
        outln!("autopilot gains");
        outln!(
            "  roll    kp_phi {:.5}  kd_phi {:.5}  ki_phi {:.5}",
            g.kp_phi,
            g.kd_phi,
            g.ki_phi
        );
        outln!("  course  kp_chi {:.5}  ki_chi {:.5}", g.kp_chi, g.ki_chi);
        outln!(
            "  pitch   kp_theta {:.5}  kd_theta {:.5}  K_theta_DC {:.5}",
            g.kp_theta,
            g.kd_theta,
            g.k_theta_dc
        );
        outln!(
            "  airspeed (throttle) kp_v {:.5}  ki_v {:.5}",
            g.kp_v,
            g.ki_v
        );
        outln!(
            "  airspeed (pitch)    kp_v2 {:.5}  ki_v2 {:.5}",
            g.kp_v2,
            g.ki_v2
        );
        outln!("  altitude kp_h {:.5}  ki_h {:.5}", g.kp_h, g.ki_h);
    }
    Ok(())
}

/// The largest `--inputs` file, bytes (256 MiB).
const MAX_REPLAY_INPUT_BYTES: u64 = 256 << 20;

/// The initial altitudes `replay` accepts, m.
pub const REPLAY_ALTITUDE_RANGE_M: (f64, f64) = (0.0, 20_000.0);

/// Refuses `--altitude-m` outside [`REPLAY_ALTITUDE_RANGE_M`] and an `--out` that is the
/// input file.
fn check_replay_args(a: &ReplayArgs) -> Result<(), Failure> {
    let (lo, hi) = REPLAY_ALTITUDE_RANGE_M;
    if !(a.altitude_m.is_finite() && (lo..=hi).contains(&a.altitude_m)) {
        return Err(Failure {
            code: exit::USAGE,
            message: format!(
                "--altitude-m must be a finite number in [{lo}, {hi}] m, got {}",
                Echo(a.altitude_m)
            ),
        });
    }
    if crate::output::same_file(&a.inputs, &a.out) {
        return Err(Failure {
            code: exit::USAGE,
            message: format!(
                "--out {} is the input file {}: it would be overwritten",
                a.out.display(),
                a.inputs.display()
            ),
        });
    }
    Ok(())
}

/// The control inputs of `--inputs` file `path`: `(t_s, deltas)` rows with increasing times,
/// each surface within its limits ([`replay::check_deltas`]), the whole checked by
/// [`replay::validate`]; a problem names the file and line.
// Long by choice: a CSV parser, read in the order of the file (the header's columns, then each
// row's cells checked where they are read, then the rows as a whole).
fn read_replay_inputs(path: &Path) -> Result<Vec<(f64, Deltas)>, Failure> {
    let shown = path.display().to_string();
    let data = |m: String| Failure {
        code: exit::DATAERR,
        message: format!("{shown}: {m}"),
    };
    let bytes =
        isotrack_fields::io::read_limited(path, MAX_REPLAY_INPUT_BYTES).map_err(|e| Failure {
            code: exit::NOINPUT,
            message: format!("cannot read --inputs {shown}: {e}"),
        })?;
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_reader(bytes.as_slice());
    let headers = rdr
        .headers()
        .map_err(|e| data(format!("line 1: {e}")))?
        .clone();
    let cols = [
        "t_s",
        "delta_e_rad",
        "delta_a_rad",
        "delta_r_rad",
        "delta_t",
    ];
    if let Some(dup) = cols
        .iter()
        .find(|c| headers.iter().filter(|h| h == *c).count() > 1)
    {
        return Err(data(format!(
            "line 1: column `{dup}` appears more than once"
        )));
    }
    let idx: Vec<usize> = cols
        .iter()
        .map(|c| {
            headers.iter().position(|h| h == *c).ok_or_else(|| {
                data(format!(
                    "line 1: no column `{c}` (need {})",
                    cols.join(", ")
                ))
            })
        })
        .collect::<Result<_, _>>()?;
    let mut rows: Vec<(f64, Deltas)> = Vec::new();
    for rec in rdr.records() {
        let rec = rec.map_err(|e| data(e.to_string()))?;
        let line = rec.position().map_or(0, |p| p.line());
        let mut v = [0.0; 5];
        for (k, &i) in idx.iter().enumerate() {
            let tok = rec.get(i).unwrap_or("");
            v[k] = tok
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    data(format!(
                        "line {line}: `{}` = `{tok}` is not a finite number",
                        cols[k]
                    ))
                })?;
        }
        if let Some((t_prev, _)) = rows.last() {
            if v[0] <= *t_prev {
                return Err(data(format!(
                    "line {line}: t_s = {} does not increase",
                    v[0]
                )));
            }
        }
        let d = Deltas {
            elevator_rad: v[1],
            aileron_rad: v[2],
            rudder_rad: v[3],
            throttle: v[4],
        };
        replay::check_deltas(&d).map_err(|m| data(format!("line {line}: {m}")))?;
        rows.push((v[0], d));
    }
    replay::validate(&rows).map_err(|e| data(e.to_string()))?;
    Ok(rows)
}

/// `isotrack replay`.
pub fn replay(a: &ReplayArgs) -> Result<(), Failure> {
    let shown = a.inputs.display().to_string();
    let data = |m: String| Failure {
        code: exit::DATAERR,
        message: format!("{shown}: {m}"),
    };
    check_replay_args(a)?;
    let rows = read_replay_inputs(&a.inputs)?;
    let uav = FixedWing::new(FixedWingConfig {
        airspeed_mps: a.airspeed_mps,
        altitude_m: a.altitude_m,
        ..FixedWingConfig::default()
    })
    .map_err(|e| Failure {
        code: exit::USAGE,
        message: e.to_string(),
    })?;
    let x0 = trim_state(uav.trim(), a.altitude_m, 0.0);
    let cant = |e: std::io::Error| Failure {
        code: exit::CANTCREAT,
        message: format!("cannot write {}: {e}", a.out.display()),
    };
    let mut out =
        std::io::BufWriter::new(isotrack_runs::files::create_output(&a.out).map_err(cant)?);
    writeln!(out, "{}", REPLAY_COLUMNS.join(",")).map_err(cant)?;
    replay::replay(&uav, x0, &rows, |r| {
        writeln!(
            out,
            "{}",
            r.iter().map(|v| num(*v)).collect::<Vec<_>>().join(",")
        )
    })
    .map_err(|e| data(e.to_string()))?
    .map_err(cant)?;
    out.flush().map_err(cant)?;
    outln!("wrote {} ({} rows)", a.out.display(), rows.len());
    Ok(())
}
