//! The flight phases' time to alert against SPEC §6's typical
//! requirements: 30 s en route, 15 s terminal, 10 s NPA.

use super::*;

#[test]
fn time_to_alert_is_spec_6s() {
    assert_eq!(Phase::EnRoute.time_to_alert_s(), 30.0);
    assert_eq!(Phase::Terminal.time_to_alert_s(), 15.0);
    assert_eq!(Phase::Npa.time_to_alert_s(), 10.0);
}
