//! The laws this crate registers by name at start (the five paper laws and the generic ones):
//! one line per law. A new built-in law is its module plus one line here; a user's law is
//! registered from outside with [`register_law`](crate::control::registry::register_law).

use crate::control::registry::{Entry, de_params, de_spec};

/// The laws this crate registers: one line per law.
pub(crate) fn laws() -> Vec<(&'static str, Entry)> {
    use crate::control::{generic, geng2015, guo2016, xu2015, xu2019, zhang2018};
    vec![
        ("Guo2016", Entry::Spec(de_spec::<guo2016::Guo2016Spec>)),
        ("Geng2015", Entry::Spec(de_spec::<geng2015::Geng2015Spec>)),
        ("Xu2015", Entry::Spec(de_spec::<xu2015::Xu2015Spec>)),
        (
            "Zhang2018",
            Entry::Spec(de_spec::<zhang2018::Zhang2018Spec>),
        ),
        ("Xu2019", Entry::Spec(de_spec::<xu2019::Xu2019Spec>)),
        (
            "HillPd",
            Entry::Law(de_params::<generic::hill::HillPdParams>),
        ),
        (
            "Glideslope",
            Entry::Law(de_params::<generic::glideslope::GlideslopeParams>),
        ),
        (
            "Attitude",
            Entry::Law(de_params::<generic::attitude::AttitudeParams>),
        ),
        (
            "Sequencer",
            Entry::Law(de_params::<generic::sequencer::SequencerParams>),
        ),
    ]
}
