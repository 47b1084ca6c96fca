//! CSV files are written through the csv crate: a field with a comma or a quote (the series
//! names of the adaptivity benchmark, `h Q1, Jacobi-CG`) is quoted and reads back as one field.

#[path = "common/tempdir.rs"]
mod tempdir;

use tempdir::TestDir;
use tread::io::output::{read_text_csv, write_csv, write_text_csv};

#[test]
fn a_field_with_a_comma_round_trips_through_a_csv_reader() {
    let dir = TestDir::new("csv-quoting", "comma");
    let path = dir.join("adapt.csv");
    let header = [
        "series",
        "step",
        "n",
        "rel_error",
        "cumulative_time_s",
        "step_time_s",
    ];
    let names = ["h Q1, Jacobi-CG", "hp \"graded\", direct"];
    write_text_csv(
        &path,
        &header,
        names.iter().map(|n| {
            vec![
                n.to_string(),
                "0".into(),
                "16".into(),
                "1e-2".into(),
                "0.5".into(),
                "0.5".into(),
            ]
        }),
    )
    .unwrap();
    let mut r = csv::Reader::from_path(&path).unwrap();
    assert_eq!(r.headers().unwrap().len(), 6);
    let rows: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
    assert_eq!(rows.len(), 2);
    for (row, name) in rows.iter().zip(names) {
        assert_eq!(row.len(), 6, "{row:?}");
        assert_eq!(&row[0], name);
        assert_eq!(&row[2], "16");
    }
    let (h, back) = read_text_csv(&path).unwrap();
    assert_eq!(h, header.map(String::from));
    assert_eq!(back[0][0], names[0]);
}

#[test]
fn numeric_tables_read_back_with_empty_fields_for_non_finite_values() {
    let dir = TestDir::new("csv-quoting", "numbers");
    let path = dir.join("t.csv");
    write_csv(
        &path,
        &["a", "b"],
        [vec![1.5, f64::NAN], vec![-2.0, 3.0]].into_iter(),
    )
    .unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert_eq!(text, "a,b\n1.5,\n-2,3\n");
    let (h, rows) = tread::driver::compare::read_csv(&path).unwrap();
    assert_eq!(h, ["a", "b"]);
    assert!(rows[0][1].is_nan() && rows[1][0] == -2.0);
}
