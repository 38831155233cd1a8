"""Tests of :mod:`ntc_design.reports.style`."""


def test_agent_styles_tell_agents_apart_in_a_colour_blind_safe_palette():
    from ntc_design.reports.style import PALETTE, agent_style

    styles = [agent_style(k) for k in range(28)]
    assert len({(s.colour, s.linestyle, s.marker) for s in styles}) == 28
    for a, b in zip(styles, styles[1:], strict=False):  # neighbours differ in each
        assert a.colour != b.colour and a.linestyle != b.linestyle and a.marker != b.marker
    assert {s.colour for s in styles} <= set(PALETTE) and "#F0E442" not in PALETTE
