"""URDF import (docs/urdf.md): `appell import` and appell.load of a .urdf file.

References from outside the converter:
* the differential-drive robot of tests/urdf/ written joint by joint as the hand-written scene
  tests/urdf/diff_drive.yaml moves identically (the CSVs' numbers are equal);
* the same robot in the usual ROS style (wheel joints about y, cylinders turned onto y, so the
  body frames move) follows the same motion within the integrator's tolerance;
* the arm's inertial frames, turned by rpy with products of inertia, give the motion of the same
  arm with the tensors and centres of mass turned here with NumPy (R = Rz Ry Rx) and the
  collision spheres removed (body frames not moved), within the integrator's tolerance;
* the arm conserves energy to the integrator's tolerance;
* malformed files are refused with FILE:LINE and the element, exit 2, and no output file."""

import re

import numpy as np
import pytest

import appell
from conftest import SOURCE, run_cli

URDF = SOURCE / "tests" / "urdf"
RTOL, ATOL = 1e-10, 1e-12
RUN = ["--rtol", RTOL, "--atol", ATOL, "--t-end", 3, "--interval", 0.05, "--quiet"]
DD_SETS = ["--set", "initial.wheel_l.rate=8", "--set", "initial.wheel_r.rate=12"]
ARM_SETS = ["--set", "initial.shoulder.angle=1", "--set", "initial.elbow.angle=0.5",
            "--set", "initial.wrist.rate=3"]


def read_csv(path):
    return np.genfromtxt(path, delimiter=",", names=True)


def import_and_run(tmp_path, urdf, tag, sets, *opts):
    scene = tmp_path / f"{tag}.yaml"
    run_cli("import", urdf, "--out", scene, *opts)
    out = tmp_path / f"{tag}.csv"
    run_cli("run", scene, *RUN, *sets, "--out", out)
    return read_csv(out)


def assert_same_motion(a, b, exact=False):
    assert a.dtype.names == b.dtype.names
    for name in b.dtype.names:
        if exact:
            assert np.array_equal(a[name], b[name]), name
        elif name not in ("energy_error", "residual"):   # errors themselves, not the motion
            # the integrator's tolerance on the column's scale, with its absolute floor
            err = np.abs(a[name] - b[name]).max()
            assert err <= 10 * (RTOL * np.abs(b[name]).max() + ATOL), (name, err)


def test_diff_drive_equals_scene(tmp_path):
    got = import_and_run(tmp_path, URDF / "diff_drive.urdf", "dd", DD_SETS,
                         "--wheels", "wheel_l,wheel_r")
    ref = tmp_path / "ref.csv"
    run_cli("run", URDF / "diff_drive.yaml", *RUN, "--out", ref)
    ref = read_csv(ref)
    assert_same_motion(got, ref, exact=True)
    assert np.ptp(ref["chassisheading"]) > 0.5   # it turns: the comparison is not trivial


def test_diff_drive_ros_style(tmp_path):
    ros = import_and_run(tmp_path, URDF / "diff_drive_ros.urdf", "ros", DD_SETS,
                         "--wheels", "wheel_l", "--wheels", "wheel_r")
    ref = tmp_path / "ref.csv"
    run_cli("run", URDF / "diff_drive.yaml", *RUN, "--out", ref)
    assert_same_motion(ros, read_csv(ref))


def rpy_matrix(r, p, y):
    cx, sx, cy, sy, cz, sz = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def turned_inertials(text):
    """The arm with every inertial rpy applied to its tensor here, and no collisions."""
    text = re.sub(r"<collision>.*?</collision>", "", text, flags=re.S)

    def turn(m):
        block = m.group(0)
        o = re.search(r'<origin xyz="([^"]*)" rpy="([^"]*)"/>', block)
        if not o:
            return block
        it = dict(re.findall(r'(i[xyz]{2})="([^"]*)"', block))
        g = {k: float(it.get(k, 0)) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
        inertia = np.array([[g["ixx"], g["ixy"], g["ixz"]], [g["ixy"], g["iyy"], g["iyz"]],
                            [g["ixz"], g["iyz"], g["izz"]]])
        rot = rpy_matrix(*map(float, o.group(2).split()))
        i2 = rot @ inertia @ rot.T
        new = (f'<origin xyz="{o.group(1)}"/>' +
               re.sub(r"<inertia [^>]*/>", "<inertia " + " ".join(
                   f'{k}="{i2[a, b]!r}"' for k, a, b in (("ixx", 0, 0), ("ixy", 0, 1),
                   ("ixz", 0, 2), ("iyy", 1, 1), ("iyz", 1, 2), ("izz", 2, 2))) + "/>",
                   block[o.end():]))
        return block[:o.start()] + new
    return re.sub(r"<inertial>.*?</inertial>", turn, text, flags=re.S)


def test_arm_inertial_frames(tmp_path):
    arm = import_and_run(tmp_path, URDF / "arm.urdf", "arm", ARM_SETS)
    flat = tmp_path / "flat.urdf"
    flat.write_text(turned_inertials((URDF / "arm.urdf").read_text()))
    assert "rpy=\"0.3" not in flat.read_text() and "<sphere" not in flat.read_text()
    ref = import_and_run(tmp_path, flat, "flat", ARM_SETS)
    assert_same_motion(arm, ref)
    assert np.ptp(arm["foreangle"]) > 0.5 and np.ptp(arm["handangle"]) > 1


def test_arm_conserves_energy(tmp_path):
    arm = import_and_run(tmp_path, URDF / "arm.urdf", "arm", ARM_SETS)
    scale = np.max(np.abs(arm["kinetic"])) + np.max(np.abs(arm["potential"]))
    assert np.max(np.abs(arm["energy_error"])) <= 10 * RTOL * scale


def test_python_load_urdf(tmp_path):
    model = appell.load(URDF / "diff_drive.urdf", wheels=["wheel_l", "wheel_r"],
                        set={"initial.wheel_l.rate": 8, "initial.wheel_r.rate": 12})
    res = appell.Simulation(model, rtol=RTOL, atol=ATOL).run(t_end=3, dt=0.05)
    ref = tmp_path / "ref.csv"
    run_cli("run", URDF / "diff_drive.yaml", *RUN, "--out", ref)
    ref = read_csv(ref)
    for name in ("chassis.x", "chassis.y", "chassis.heading", "wheel_l.angle"):
        assert np.allclose(res[name], ref[name.replace(".", "")], rtol=1e-14, atol=1e-14)
    with pytest.raises(appell.SceneError) as e:
        appell.load(URDF / "diff_drive.urdf", wheels=["wheel_x"])
    assert "wheel_x" in str(e.value) and "wheel_l" in str(e.value)


BASE = (URDF / "arm.urdf").read_text()


def edit(old, new):
    assert old in BASE
    return BASE.replace(old, new, 1)


def line_of(text, what):
    return text[:text.index(what)].count("\n") + 1


# (id, text, the text on the line named, what the message says)
BAD = [
    ("missing_inertial", edit('<link name="fore">\n    <inertial>', '<link name="fore">\n    <x>')
     .replace("</inertial>\n  </link>\n  <link name=\"hand\">",
              "</x>\n  </link>\n  <link name=\"hand\">", 1),
     '<link name="fore">', "<link name='fore'>: the link has no <inertial>"),
    ("zero_axis", edit('<axis xyz="0.6 0 0.8"/>', '<axis xyz="0 0 0"/>'), '<axis xyz="0 0 0"/>',
     "<axis>: the axis (0, 0, 0) is zero"),
    ("cycle", edit('<joint name="mount" type="fixed">\n    <parent link="world"/>',
                   '<joint name="mount" type="fixed">\n    <parent link="hand"/>'),
     '<joint name="mount"', "<joint name='mount'>: the joints form a cycle: hand -> base -> "
     "upper -> fore -> hand"),
    ("unknown_type", edit('name="wrist" type="continuous"', 'name="wrist" type="continous"'),
     'name="wrist"', "unknown joint type 'continous' (did you mean 'continuous'?)"),
    ("unknown_parent", edit('<parent link="fore"/>', '<parent link="froe"/>'),
     '<parent link="froe"/>', "<parent>: no link named 'froe' (did you mean 'fore'?)"),
    ("xml_syntax", edit('<child link="hand"/>', '<child link="hand">'),
     '</joint>\n</robot>', "XML syntax error: Opening and ending tag mismatch: child line"),
    ("two_parents", edit('<child link="hand"/>', '<child link="upper"/>'),
     '<joint name="wrist"', "link 'upper' is already the child of joint 'shoulder'"),
    ("bad_number", edit('<mass value="1"/>', '<mass value="1kg"/>'), '<mass value="1kg"/>',
     "<mass>: value='1kg' is not 1 finite number"),
    ("inertia_not_pd", edit('ixx="0.02" iyy="0.025"', 'ixx="0.02" iyy="-0.025"'),
     'iyy="-0.025"', "<inertia>: the inertia tensor is not positive definite"),
]


@pytest.mark.parametrize("case,text,where,what", BAD, ids=[b[0] for b in BAD])
def test_malformed(tmp_path, case, text, where, what):
    path = tmp_path / f"{case}.urdf"
    path.write_text(text)
    out = tmp_path / f"{case}.yaml"
    r = run_cli("import", path, "--out", out, check=False)
    assert r.returncode == 2, r.stderr
    assert not out.exists() and list(tmp_path.iterdir()) == [path]
    line = line_of(text, where)
    assert f"{path}:{line}:" in r.stderr, r.stderr   # the first error, where the tag ends
    assert what in r.stderr, r.stderr
    with pytest.raises(appell.SceneError) as e:
        appell.load(path)
    assert e.value.filename == str(path) and what in str(e.value)


def test_wheel_errors(tmp_path):
    r = run_cli("import", URDF / "diff_drive.urdf", "--wheels", "chassis", "--out",
                tmp_path / "x.yaml", check=False)
    assert r.returncode == 2 and "<link name='chassis'>: a wheel needs a <collision>" in r.stderr
    assert not (tmp_path / "x.yaml").exists()
    torus = import_and_run(tmp_path, URDF / "diff_drive.urdf", "torus", DD_SETS,
                           "--wheels", "wheel_l,wheel_r", "--wheel-shape", "torus")
    assert np.max(np.abs(torus["residual"])) < 1e-12
    text = (tmp_path / "torus.yaml").read_text()
    assert re.search(r"shape: \{kind: torus, radius: 0\.0900*1?, tube: 0\.01\}", text), text


G = 9.81


def test_joint_kinds_closed_form(tmp_path):
    got = import_and_run(tmp_path, URDF / "kinds.urdf", "kinds", [])
    m, c, force = 2.0, 2.0, 0.8 * 2.0 * G

    def s(t):
        return force / c * (t - m / c * (1 - np.exp(-c * t / m)))
    t = got["t"]
    assert np.max(np.abs(got["sliderpos"] - s(t))) <= 10 * (RTOL * 0.5 + ATOL)
    assert np.max(np.abs(got["sheety"] - G * t**2 / 2)) <= 10 * (RTOL * got["sheety"].max() + ATOL)
    assert np.max(np.abs(got["sheetx"])) <= 10 * ATOL and np.max(np.abs(got["sheetheading"])) <= 10 * ATOL
    # the upper limit 0.5 m ends the run where s(t) = 0.5 (Newton from the run's last time)
    t_star = t[-1]
    for _ in range(20):
        t_star -= (s(t_star) - 0.5) / (force / c * (1 - np.exp(-c * t_star / m)))
    assert t[-1] < 3 and abs(t[-1] - t_star) <= 1e-9, (t[-1], t_star)


def test_floating_root(tmp_path):
    got = import_and_run(tmp_path, URDF / "floating.urdf", "free",
                         ["--set", "initial.body.omega=[1, 2, 3]"])
    t = got["t"]
    assert np.max(np.abs(got["bodyz"] + G * t**2 / 2)) <= 10 * (RTOL * 45 + ATOL)
    assert np.max(np.abs(got["energy_error"])) <= 10 * RTOL * np.max(np.abs(got["potential"]))
    assert np.ptp(got["bodyqw"]) > 0.1   # it turns


def test_wheels_repeated_option(tmp_path):
    out = tmp_path / "dd.yaml"
    run_cli("import", URDF / "diff_drive.urdf", "--wheels", "wheel_r", "--wheels", "wheel_l",
            "--wheels", "wheel_r", "--out", out)
    text = out.read_text()
    assert "wheel_l_roll: {kind: rolling, body: wheel_l}" in text
    assert "wheel_r_roll: {kind: rolling, body: wheel_r}" in text
    r = run_cli("import", URDF / "diff_drive.urdf", "--wheels", "wheel_l,,wheel_r", check=False)
    assert r.returncode == 2 and "an empty link name" in r.stderr and not r.stdout
