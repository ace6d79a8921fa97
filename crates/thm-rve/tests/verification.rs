//! The quick verification cases pass (the 400-disk cases run in `cargo xtask verify`).

#[test]
fn quick_verification_cases_pass() {
    for case in thm_rve::verification::cases()
        .into_iter()
        .filter(|c| c.quick)
    {
        let out = (case.run)().unwrap();
        assert!(out.passed(), "{}: {:?}", case.name, out.rows);
    }
}
