//! How the translation method walks back ([`Walk`]): the paper's whole walk, or only the
//! first touch on the step.

/// How [`super::Reconstructor::translate_back_within`] walks back along the translation.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(in crate::geometry) enum Walk {
    /// The paper's method: the first touch on the step, or else the way out of the overlap
    /// along the whole backward ray.
    Whole,
    /// The first touch on the step only: a pose whose first touch is not on the step is
    /// answered `Penetrating`, off the trajectory, with no reversing vector and no patches
    /// ([`super::Reconstructor::set_first_touch_only`]). (Two convex meshes still get their way out:
    /// their convex path finds it at no extra cost.)
    FirstTouch,
    /// [`Walk::FirstTouch`] over a rotating path's sub-step, whose start is known apart and
    /// whose length is about one tolerance: a touch within the tolerance of its end is on it.
    /// (The paper's method wants a touch beyond the tolerance, and two sub-steps in three fell
    /// back to the features touching at their start on rapier's TriMesh-floor stress scene,
    /// after a walk out across its 60 m floor and a second sub-step.)
    SubStep,
}

impl Walk {
    /// [`Walk::FirstTouch`] when `first_touch_only`, [`Walk::Whole`] otherwise.
    pub(in crate::geometry) fn first_touch_if(first_touch_only: bool) -> Self {
        if first_touch_only {
            Walk::FirstTouch
        } else {
            Walk::Whole
        }
    }
}
