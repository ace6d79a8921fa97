//! The quick verification cases pass (the bar case is long and runs in `cargo xtask verify`).

#[test]
fn quick_verification_cases_pass() {
    for case in thm_dem::verification::cases()
        .into_iter()
        .filter(|c| c.quick)
    {
        let out = (case.run)().unwrap();
        assert!(out.passed(), "{}: {:?}", case.name, out.rows);
    }
}
