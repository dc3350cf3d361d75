"""The IK peers' adapters (drake_mh.ik.peers): the model text each peer gets, against the robot's
own URDF and Drake's plant; a peer that is not installed is reported, not raised; with the peer
installed, its FK agrees with Drake's and its answers pass Drake's check."""

from __future__ import annotations

import importlib.util

import pytest

from drake_mh.errors import UnknownMethod
from drake_mh.ik import IKProblem, verify
from drake_mh.ik.peers import PEER_MODULE, PEERS, chain_joints, peer_available, peer_problem, solve_peer, stripped_urdf


def test_the_stripped_urdf_keeps_the_kinematics_and_declares_every_parent(six_dof):
    import xml.etree.ElementTree as ET

    original = ET.fromstring(six_dof.model_text)
    root = stripped_urdf(six_dof)
    assert not root.findall("link/collision") and not root.findall("link/visual")
    assert original.findall("link/collision")  # there was something to strip
    links = {link.get("name") for link in root.findall("link")}
    assert {j.find("parent").get("link") for j in root.findall("joint")} <= links
    assert [ET.tostring(j) for j in root.findall("joint")] == [ET.tostring(j) for j in original.findall("joint")]


def test_the_chain_to_the_end_effector_holds_the_plants_joints_in_order(panda):
    joints = chain_joints(stripped_urdf(panda), panda.ee_frame_name)
    moving = [j.get("name") for j in joints if j.get("type") != "fixed"]
    assert moving == list(panda.joint_names)


def test_a_peer_that_is_not_installed_is_reported_not_raised(panda):
    for label in PEERS:
        installed = importlib.util.find_spec(PEER_MODULE[label]) is not None
        assert peer_available(label) == installed
        if not installed:
            assert peer_problem(panda, label) == f"{PEER_MODULE[label]} is not installed"


def test_an_unknown_peer_names_the_peers(panda):
    with pytest.raises(UnknownMethod, match="rtb_ik_LM"):
        solve_peer(panda, "trac-ik", panda.fk(panda.home), 0)


@pytest.mark.parametrize("label", ["ikpy", "trac_ik", "rtb_ik_LM"])
def test_an_installed_peer_solves_and_drake_checks_it(six_dof, label):
    if not peer_available(label):
        pytest.skip(f"{PEER_MODULE[label]} is not installed (extra 'peers')")
    assert peer_problem(six_dof, label) is None  # its FK matched Drake's
    X_WT = six_dof.fk(six_dof.random_configurations(1, 3)[0])
    q, reported = solve_peer(six_dof, label, X_WT, seed=0, tolerance=1e-5, timeout=0.05)
    checked = verify(IKProblem(six_dof, X_WT, position_tolerance=1e-5, orientation_tolerance=1e-5), q,
                     method=label, start=0.0, nfe=0)
    assert q.shape == (six_dof.nq,)
    if reported:  # a peer's success meets our tolerances by construction of its settings
        assert checked.success, checked.message
