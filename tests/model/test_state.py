"""The kernel's state vector, counters and status codes by name (pipeline.model.state): the four
components of the slider's state and the meniscus state's fifth (a compile-time choice), counters and
status codes each with one index and one text, as the integrator fills them."""

from __future__ import annotations

from pipeline.model import state as st


def test_state_size_adds_the_meniscus_state_only_when_there_is_one():
    assert st.state_size(None) == st.N_STATE == 4
    assert st.state_size(1.0) == st.N_STATE + 1
    assert (st.Z, st.THETA, st.Z_RATE, st.THETA_RATE, st.MENISCUS) == (0, 1, 2, 3, 4)


def test_counters_are_distinct_indices_of_the_info_array():
    counters = (st.STATUS, st.ACCEPTED, st.REJECTED, st.SWITCHES, st.RHS_CALLS, st.WINDOW_SWITCHES)
    assert sorted(counters) == list(range(st.N_COUNTERS))
    assert list(range(st.N_COUNTERS))[st.STEP_COUNTERS] == [st.ACCEPTED, st.REJECTED, st.SWITCHES]


def test_every_status_code_has_its_text():
    codes = (st.OK, st.MAX_STEPS, st.STEP_UNDERFLOW, st.NOT_FINITE)
    assert len(set(codes)) == 4 and set(st.STATUS_TEXT) == set(codes)
    assert st.STATUS_TEXT[st.OK] == "ok" and st.STATUS_TEXT[st.MAX_STEPS] == "too many steps"
