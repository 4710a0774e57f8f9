import numpy as np
import pytest

from posekit.io.bvh import BVHError, read_bvh, write_bvh

SIMPLE = """HIERARCHY
ROOT Hips
{
\tOFFSET 0 90 0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\tJOINT Spine
\t{
\t\tOFFSET 0 10 0
\t\tCHANNELS 3 Xrotation Yrotation Zrotation
\t\tJOINT Head
\t\t{
\t\t\tOFFSET 0 20 0
\t\t\tCHANNELS 6 Xposition Yposition Zposition Yrotation Xrotation Zrotation
\t\t\tEnd Site
\t\t\t{
\t\t\t\tOFFSET 0 5 0
\t\t\t}
\t\t}
\t}
\tJOINT Leg
\t{
\t\tOFFSET 10 0 0
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0 -40 0
\t\t}
\t}
}
MOTION
Frames: 2
Frame Time: 0.0333333
1 90 0 0 0 0 0 0 0 0 20 0 0 0 0
2.5e0 90 1E1 90 0 0 0 0 0 0 30 0 0 0 0
"""


def write(tmp_path, text, name="m.bvh", newline="\n"):
    p = tmp_path / name
    p.write_bytes(text.replace("\n", newline).encode())
    return p


def test_reads_channels_positions_and_end_sites(tmp_path):
    m = read_bvh(write(tmp_path, SIMPLE), scale=0.01)
    s = m.skeleton
    assert s.names == ("Hips", "Spine", "Head", "Leg") and list(s.parents) == [-1, 0, 1, 0]
    assert m.n_frames == 2 and m.frame_time == pytest.approx(0.0333333)
    assert m.channels[3] == () and m.channels[2][3:] == ("Yrotation", "Xrotation", "Zrotation")
    np.testing.assert_allclose(s.end_sites[2], [0, 0.05, 0])
    pos = m.global_positions()
    # frame 0: no rotation; Head's position channels put it 0.20 above Spine
    np.testing.assert_allclose(pos[0], [[0.01, 0.9, 0], [0.01, 1.0, 0], [0.01, 1.2, 0], [0.11, 0.9, 0]], atol=1e-12)
    # frame 1: root turned 90 deg about Z (first channel), Head lifted to 0.30: the spine points to -X
    np.testing.assert_allclose(pos[1, 2], [0.025 - 0.4, 0.9, 0.1], atol=1e-12)


def test_crlf_and_tabs_and_drop_tpose(tmp_path):
    m = read_bvh(write(tmp_path, SIMPLE, newline="\r\n"), drop_tpose=True)
    assert m.n_frames == 1 and m.local_pos[0, 0, 0] == pytest.approx(2.5)


def test_write_read_round_trip(tmp_path, sample, rng):
    frames = sample.clip_frames("cartwheel")[::7]
    skel = sample.skeleton
    path = write_bvh(tmp_path / "rt.bvh", skel, sample.local_rot[frames], 1 / 30,
                     root_pos=sample.root_pos[frames], scale=100.0)
    back = read_bvh(path, scale=0.01)
    assert back.skeleton.names == skel.names
    np.testing.assert_allclose(back.global_positions(), sample.global_pos[frames], atol=1e-6)


def test_round_trip_keeps_a_files_layout(tmp_path):
    m = read_bvh(write(tmp_path, SIMPLE), scale=0.01)
    out = write_bvh(tmp_path / "again.bvh", m.skeleton, m.local_rot, m.frame_time, local_pos=m.local_pos,
                    channels=m.channels, scale=100.0)
    back = read_bvh(out, scale=0.01)
    assert back.channels == m.channels
    np.testing.assert_allclose(back.global_positions(), m.global_positions(), atol=1e-9)
    np.testing.assert_allclose(back.skeleton.end_sites[3], [0, -0.4, 0])


@pytest.mark.parametrize("edit, line, msg", [
    (lambda t: t[: t.index("MOTION")], None, "no MOTION section"),
    (lambda t: t.replace("Frames: 2", "Frames: 3"), 33, "says 3 frames but the file has 2"),
    (lambda t: t.replace("Frames: 2", "Frames: 0"), 32, "says 0 frames but 2 frame rows follow"),
    (lambda t: t.replace("1 90 0 0 0", "1 90 0 0"), 32, "expected 15 values in a frame row, found 14"),
    (lambda t: t.replace("1 90 0 0 0", "1 90 zero 0 0"), 32, "bad number 'zero'"),
    (lambda t: t.replace("Xrotation Yrotation Zrotation", "Xrotation Yrotation Wrotation"), 9,
     "unknown channel 'Wrotation' on joint Spine"),
    (lambda t: t.replace("OFFSET 0 10 0", "OFFSET 0 ten 0"), 8, "expected a number for OFFSET of Spine"),
    (lambda t: t.replace("HIERARCHY", "HIERARCHI"), 1, "expected 'HIERARCHY'"),
    (lambda t: t.replace("Frame Time: 0.0333333", "Frame Time: fast"), 31, "bad number"),
])
def test_malformed_files_name_file_and_line(tmp_path, edit, line, msg):
    p = write(tmp_path, edit(SIMPLE), "bad.bvh")
    with pytest.raises(BVHError, match=msg) as e:
        read_bvh(p)
    assert str(e.value).startswith(str(p) + ":")
    if line is not None:
        assert e.value.line == line, str(e.value)


def test_truncated_hierarchy(tmp_path):
    text = SIMPLE[: SIMPLE.index("JOINT Leg")] + "\nMOTION\nFrames: 0\nFrame Time: 0.1\n"
    with pytest.raises(BVHError, match="file ends early|expected"):
        read_bvh(write(tmp_path, text))


def test_missing_file(tmp_path):
    with pytest.raises(BVHError, match="cannot read"):
        read_bvh(tmp_path / "nope.bvh")


@pytest.mark.shared_data
def test_reads_real_bandai_file_in_metres(shared_data):
    f = sorted((shared_data / "bandai-namco-1" / "data").glob("*walk_normal*.bvh"))[0]
    m = read_bvh(f, scale=0.01)
    assert m.skeleton.n_joints == 22 and all(len(c) == 6 for c in m.channels)
    pos = m.global_positions()
    height = pos[:, m.skeleton.index("Head"), 1].mean()
    assert 1.3 < height < 2.0  # a person's head, in metres
    assert pos[..., 1].min() > -0.05  # feet on the floor


def test_one_extra_frame_row_warns_and_reads_every_row(tmp_path):
    from posekit.io.bvh import BVHWarning

    p = write(tmp_path, SIMPLE.replace("Frames: 2", "Frames: 1"), "offbyone.bvh")
    with pytest.warns(BVHWarning, match=r"offbyone.bvh:33: Frames: says 1 frames but the file has 2 complete"):
        m = read_bvh(p)
    assert m.n_frames == 2 and m.local_pos[1, 0, 0] == pytest.approx(2.5)
    np.testing.assert_allclose(m.global_positions(), read_bvh(write(tmp_path, SIMPLE)).global_positions())


def test_fewer_rows_than_declared_stays_an_error(tmp_path):
    p = write(tmp_path, SIMPLE.replace("Frames: 2", "Frames: 3"), "short.bvh")
    with pytest.raises(BVHError, match="Frames: says 3 frames but the file has 2") as e:
        read_bvh(p)
    assert str(e.value).startswith(f"{p}:33:")
    # two extra rows are no off-by-one slip: an error on the first of them
    p = write(tmp_path, SIMPLE.replace("Frames: 2", "Frames: 1").replace("Frames: 1", "Frames: 0"), "two.bvh")
    with pytest.raises(BVHError, match="says 0 frames but 2 frame rows follow"):
        read_bvh(p)


@pytest.mark.parametrize("declared", [2, 3])
def test_a_cut_off_last_frame_row_is_reported_and_not_a_frame(tmp_path, declared):
    """Issue 45: a file that ends inside a frame row (a cut copy) reads its complete rows, says which line was cut,
    and never counts the cut row as a frame, whether or not ``Frames:`` counted it."""
    from posekit.io.bvh import BVHWarning

    text = SIMPLE.replace("Frames: 2", f"Frames: {declared}") + "1 2 3\n"
    p = write(tmp_path, text, "cut.bvh")
    with pytest.warns(BVHWarning, match=r"cut.bvh:34: the last frame row is cut off \(3 of \d+ values\)") as caught:
        m = read_bvh(p)
    assert m.n_frames == 2
    np.testing.assert_allclose(m.global_positions(), read_bvh(write(tmp_path, SIMPLE)).global_positions())
    assert ("Frames: says 3" in str(caught[0].message)) == (declared == 3)


def test_guessed_roles_and_units_on_a_plain_file(tmp_path):
    m = read_bvh(write(tmp_path, SIMPLE), scale=0.01)
    assert m.skeleton.roles == {"pelvis": "Hips", "head": "Head", "chest": "Spine"}
    assert m.units.unit == "given" and m.units.scale == 0.01 and m.rig.rig == "unknown"
    assert read_bvh(write(tmp_path, SIMPLE), roles={"head": "Spine"}).skeleton.roles["head"] == "Spine"
