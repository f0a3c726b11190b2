//! `field.kind = "stations"`: the same grid as `isotrack interpolate` wrote to the bundled
//! `data/no2_germany_kriged`, and a run on it.

use isotrack_scenario::field::FieldModel;
use isotrack_scenario::parse_scenario_in;
use isotrack_sim::{NoTrace, Outcome};
use std::path::Path;

#[test]
fn stations_kind_matches_the_bundled_kriged_grid_and_runs() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data");
    let text =
        "[field]\nkind = \"stations\"\npath = \"no2_germany_stations/no2_germany_stations.csv\"\n\
                value_column = \"no2_ugm3\"\ngrid_spacing_m = 10000.0\n";
    let s = parse_scenario_in(text, "stations.toml", &[], &data).unwrap();
    let FieldModel::Grid(g) = s.field() else {
        panic!("a grid")
    };
    let bundled = isotrack_fields::io::load_grid(
        &data.join("no2_germany_kriged/no2_germany_kriged.csv"),
        None,
    )
    .unwrap();
    assert_eq!(
        (g.grid().nx(), g.grid().ny()),
        (bundled.grid.nx(), bundled.grid.ny())
    );
    assert_eq!(
        g.grid().values(),
        bundled.grid.values(),
        "bit-identical to the interpolate output"
    );
    assert_eq!(g.grid().spacing_m(), [10000.0, 10000.0]);

    // Rescaled to tens of metres (as the paper did) with IDW: the robot flies its 60 s on the
    // map (a start well inside it), 0.5 m/s x 60 s = 30 m of path.
    let text = "[field]\nkind = \"stations\"\npath = \"no2_germany_stations/no2_germany_stations.csv\"\n\
                value_column = \"no2_ugm3\"\nmethod = \"idw\"\ngrid_spacing_m = 10000.0\nspacing_m = [1.0, 1.0]\n\
                [initial]\nx_m = 30.0\ny_m = 40.0\n[controller]\nki = 0.0\nc1 = 0.05\n[sim]\nduration_s = 60.0\n";
    let s = parse_scenario_in(text, "stations.toml", &[], &data).unwrap();
    let r = s.run(&mut NoTrace);
    assert_eq!(r.outcome, Outcome::Completed, "{:?}", r.outcome_detail);
    // (the sum of step chords: shorter than the arc by O((omega dt)^2) per step)
    assert!(
        (r.metrics.path_length_m - 30.0).abs() < 1e-3,
        "{}",
        r.metrics.path_length_m
    );
    // A missing column is a scenario error naming the key.
    let bad = "[field]\nkind = \"stations\"\npath = \"no2_germany_stations/no2_germany_stations.csv\"\nvalue_column = \"pm25\"\n";
    let e = parse_scenario_in(bad, "bad.toml", &[], &data)
        .unwrap_err()
        .to_string();
    assert!(e.contains("field.path") && e.contains("pm25"), "{e}");
    let bad = "[field]\nkind = \"stations\"\npath = \"x.csv\"\n";
    let e = parse_scenario_in(bad, "bad.toml", &[], &data)
        .unwrap_err()
        .to_string();
    assert!(e.contains("field.value_column"), "{e}");
}
