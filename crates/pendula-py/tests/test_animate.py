"""Solution.animate(): pendula's own GIF, one frame per 1/fps s of simulated time."""

import pickle

import numpy as np
import pytest
from PIL import Image

import pendula


def test_an_animation_has_one_frame_per_tick_and_shows_inline(tmp_path):
    sol = pendula.solve("double", (0, 2), method="rk4", dt=1e-3)
    anim = sol.animate(fps=10, size=(200, 240))
    assert anim.frames == 21 and anim.data[:6] == b"GIF89a"
    anim.save(tmp_path / "run.gif")
    assert [p.name for p in tmp_path.iterdir()] == ["run.gif"]  # no temporary file left
    with Image.open(tmp_path / "run.gif") as im:
        assert im.n_frames == 21 and im.size == (200, 240)
        first = np.asarray(im.convert("RGB"))
        im.seek(20)
        last = np.asarray(im.convert("RGB"))
    # The pendulum moved between the first and the last frame.
    assert np.count_nonzero(np.any(first != last, axis=2)) > 200
    html = anim._repr_html_()
    assert html.startswith('<img src="data:image/gif;base64,R0lGOD')  # "GIF8" in base64


def test_frames_come_from_the_dense_output_when_there_is_one():
    sol = pendula.solve("pendulum", (0, 1), method="verlet", dt=1e-3, dense_output=True)
    assert sol.animate(fps=20, size=(128, 160)).frames == 21
    # A chain of three links draws three rods.
    chain = pendula.solve(pendula.System("chain", links=3), (0, 0.5), method="rk4", dt=1e-3)
    assert chain.animate(fps=10, size=(160, 200)).frames == 6


def test_bad_animation_settings_are_refused():
    sol = pendula.solve("pendulum", (0, 1), method="rk4")
    with pytest.raises(pendula.InvalidValueError, match="fps 60"):
        sol.animate(fps=60)
    with pytest.raises(pendula.InvalidValueError, match="size 32x480"):
        sol.animate(size=(32, 480))
    with pytest.raises(pendula.InvalidValueError, match="no angles"):
        pendula.solve("oscillator", (0, 1)).animate()
    with pytest.raises(pendula.InvalidValueError, match=".gif"):
        sol.animate(fps=5, size=(128, 160)).save("run.mp4")
    assert pickle.loads(pickle.dumps(sol)).animate(fps=5, size=(128, 160)).frames == 6
