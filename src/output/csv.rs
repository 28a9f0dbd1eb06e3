//! CSV serialisation, pure: rows in, bytes out (file I/O lives in `sink`).

use super::row::Row;

/// The header line of rows shaped like `row`.
pub fn header(row: &Row) -> Vec<u8> {
    let mut w = ::csv::Writer::from_writer(Vec::new());
    w.write_record(row.0.iter().map(|c| c.name.as_str()))
        .expect("writing to memory cannot fail");
    w.into_inner().expect("flush to memory")
}

/// One record line; the columns must match the header.
pub fn record(row: &Row) -> Vec<u8> {
    let mut w = ::csv::Writer::from_writer(Vec::new());
    w.write_record(row.0.iter().map(|c| c.value.render()))
        .expect("writing to memory cannot fail");
    w.into_inner().expect("flush to memory")
}

/// A whole table: header (from the first row) and records.
pub fn serialize(rows: &[Row]) -> Vec<u8> {
    let mut out = Vec::new();
    if let Some(first) = rows.first() {
        out.extend(header(first));
        for r in rows {
            out.extend(record(r));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_and_records_line_up() {
        use crate::output::column::{Class, Column};
        const P: Column = Column::value("point", "1", Class::Parameter, "");
        const M: Column = Column::value("n_i_mean", "1", Class::Measured, "");
        const B: Column = Column::value("n_i_band", "1", Class::Check, "");
        const X: Column = Column::value("x", "1", Class::Measured, "");
        const Y: Column = Column::value("y", "1", Class::Check, "");
        let mut r = Row::default();
        r.put(&P, 0u64)
            .put(&M, 1.5)
            .put(&B, "inside")
            .put(&X, f64::NAN)
            .put(&Y, "");
        let text = String::from_utf8(serialize(&[r.clone(), r])).expect("utf8");
        // One missing-value convention: a missing number and a missing text are both `NaN`.
        assert_eq!(
            text,
            "point,n_i_mean,n_i_band,x,y\n0,1.5,inside,NaN,NaN\n0,1.5,inside,NaN,NaN\n"
        );
    }
}
