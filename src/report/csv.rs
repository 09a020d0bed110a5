//! `report.csv`: one line per case.

use super::row::Row;

/// The header line of `report.csv`.
pub const CSV_HEADER: &str = "family,kernel,penumbra,slabs,variance_level,variance,tilt_deg,distance_over_d1,\
compensation,preintegration,width,height,time_ms,rmse_correct,rmse_iterated,isoline_err_px,width_err_correct_px,\
width_err_iterated_px,width_px,rmse_reference,reference_self_err,view_angle_deg,fov_deg,light_resolution,note";

impl Row {
    /// The row as one CSV line (no newline).
    pub fn csv(&self) -> String {
        let o = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:.6}"));
        format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{:.3},{},{},{},{},{},{},{},{},{},{},{},\"{}\"",
            self.family,
            self.kernel,
            self.penumbra,
            self.slabs,
            self.variance_level,
            o(self.variance),
            o(self.tilt_deg),
            o(self.distance_over_d1),
            self.compensation,
            self.preintegration,
            self.width,
            self.height,
            self.time_ms,
            o(self.rmse_correct),
            o(self.rmse_iterated),
            o(self.isoline_err_px),
            o(self.width_err_correct_px),
            o(self.width_err_iterated_px),
            o(self.width_px),
            o(self.rmse_reference),
            o(self.reference_self_err),
            o(self.view_angle_deg),
            o(self.fov_deg),
            o(self.light_resolution),
            self.note.replace('"', "'"),
        )
    }
}

/// The whole of `report.csv`: header and rows, one per line.
pub fn csv(rows: &[Row]) -> String {
    let mut csv = String::from(CSV_HEADER);
    csv.push('\n');
    for r in rows {
        csv.push_str(&r.csv());
        csv.push('\n');
    }
    csv
}
