//! MODELS.md §1: the fault frequencies of the data sets' bearings.

use bearingd::bearing::BearingGeometry;

fn close(actual: f64, expected: f64, tolerance: f64, what: &str) {
    assert!(
        (actual - expected).abs() <= tolerance,
        "{what}: {actual} != {expected} ± {tolerance}"
    );
}

#[test]
fn cwru_drive_end_multiples_of_shaft_rate() {
    let orders = BearingGeometry::from_catalog("skf-6205-2rs")
        .unwrap()
        .fault_orders();
    close(orders.bpfi, 5.4152, 5e-4, "BPFI");
    close(orders.bpfo, 3.5848, 5e-4, "BPFO");
    close(orders.ftf, 0.39828, 5e-5, "FTF");
    close(orders.two_bsf, 4.7135, 5e-4, "2xBSF");
    close(orders.bsf, 2.357, 5e-4, "BSF");
}

#[test]
fn cwru_at_1772_rpm() {
    let f = BearingGeometry::from_catalog("SKF 6205-2RS")
        .unwrap()
        .fault_frequencies(1772.0 / 60.0);
    close(f.bpfo, 105.87, 0.01, "BPFO");
    close(f.bpfi, 159.93, 0.01, "BPFI");
}

#[test]
fn seed_002_siegen_61804_at_3000_rpm() {
    let f = BearingGeometry::from_catalog("skf-61804")
        .unwrap()
        .fault_frequencies(50.0);
    close(f.bpfo, 281.25, 0.01, "BPFO");
    close(f.bpfi, 368.75, 0.01, "BPFI");
}

#[test]
fn custom_geometry_equals_catalog_entry() {
    let custom = BearingGeometry::parse("z=9,d=7.94mm,D=39.04mm,alpha=0").unwrap();
    let catalog = BearingGeometry::parse("skf-6205-2rs").unwrap();
    assert_eq!(custom.fault_orders(), catalog.fault_orders());
}

#[test]
fn ims_rexnord_za_2115_at_2000_rpm() {
    // Published for the IMS rig (Qiu et al. 2006): BPFO 236.4 Hz, BPFI 296.9 Hz, 2xBSF 279.8 Hz, FTF 14.8 Hz.
    let f = BearingGeometry::from_catalog("rexnord-za-2115")
        .unwrap()
        .fault_frequencies(2000.0 / 60.0);
    close(f.bpfo, 236.4, 0.1, "BPFO");
    close(f.bpfi, 296.9, 0.1, "BPFI");
    close(f.two_bsf, 279.8, 0.1, "2xBSF");
    close(f.ftf, 14.8, 0.05, "FTF");
}
