"""Hypothesis strategies shared by the enclosure tests: intervals with a point inside."""

from hypothesis import strategies as st

finite = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False, allow_infinity=False)
wide = st.floats(min_value=-1e150, max_value=1e150, allow_nan=False, allow_infinity=False)
tiny = st.floats(min_value=-1e-300, max_value=1e-300, allow_nan=False, allow_infinity=False)


@st.composite
def interval_and_point(draw, elements=finite):
    a = draw(elements)
    b = draw(elements)
    lo, hi = min(a, b), max(a, b)
    x = draw(st.floats(min_value=lo, max_value=hi, allow_nan=False))
    return lo, hi, x
