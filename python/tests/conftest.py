"""Shared fixtures: the repository's robot models, and the oracles (Pinocchio, Ray).

An oracle that is not installed skips its tests, unless TWINLOOP_REQUIRE_ORACLES=1
(CI), where a missing oracle fails them instead.
"""

import importlib
import os
import pathlib

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
MODELS = REPO / "models"
OP3 = MODELS / "op3" / "robotis_op3.nomesh.urdf"
G1 = MODELS / "unitree_g1" / "g1_29dof_rev_1_0.nomesh.urdf"


def oracle(name):
    """Import an oracle module; skip (or fail under TWINLOOP_REQUIRE_ORACLES=1) without it."""
    try:
        return importlib.import_module(name)
    except ImportError as e:
        if os.environ.get("TWINLOOP_REQUIRE_ORACLES") == "1":
            pytest.fail(f"oracle {name} is required (TWINLOOP_REQUIRE_ORACLES=1) but not importable: {e}")
        pytest.skip(f"oracle {name} not installed")


# A small robot made in the test: a branching tree with a fixed joint, a prismatic
# joint, an unaligned revolute axis and a rotated joint origin.
TEST_URDF = """<?xml version="1.0"?>
<robot name="made_in_test">
  <link name="base">
    <inertial><origin xyz="0.01 -0.02 0.03" rpy="0.1 0.2 0.3"/><mass value="2.0"/>
      <inertia ixx="0.02" ixy="0.001" ixz="-0.002" iyy="0.03" iyz="0.0015" izz="0.025"/></inertial>
  </link>
  <link name="arm">
    <inertial><origin xyz="0.0 0.05 -0.1" rpy="0 0 0"/><mass value="0.7"/>
      <inertia ixx="0.004" ixy="0" ixz="0" iyy="0.005" iyz="0" izz="0.002"/></inertial>
  </link>
  <link name="slider">
    <inertial><origin xyz="0.02 0 0" rpy="0 0.4 0"/><mass value="0.3"/>
      <inertia ixx="0.001" ixy="0.0001" ixz="0" iyy="0.0012" iyz="0" izz="0.0009"/></inertial>
  </link>
  <link name="hand">
    <inertial><origin xyz="0 0 -0.03" rpy="0 0 0"/><mass value="0.2"/>
      <inertia ixx="0.0005" ixy="0" ixz="0" iyy="0.0005" iyz="0" izz="0.0003"/></inertial>
  </link>
  <link name="leg">
    <inertial><origin xyz="0 0 -0.15" rpy="0 0 0"/><mass value="1.1"/>
      <inertia ixx="0.01" ixy="0" ixz="0.001" iyy="0.011" iyz="0" izz="0.003"/></inertial>
  </link>
  <link name="foot">
    <inertial><origin xyz="0.03 0 -0.01" rpy="0 0 0"/><mass value="0.4"/>
      <inertia ixx="0.0008" ixy="0" ixz="0" iyy="0.0015" iyz="0" izz="0.0017"/></inertial>
  </link>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="arm"/>
    <origin xyz="0.0 0.15 0.2" rpy="0.3 0 0.1"/><axis xyz="0.6 0.0 0.8"/>
    <limit lower="-2" upper="2" effort="10" velocity="5"/>
  </joint>
  <joint name="extend" type="prismatic">
    <parent link="arm"/><child link="slider"/>
    <origin xyz="0 0.1 -0.2" rpy="0 0 0"/><axis xyz="0 0 -1"/>
    <limit lower="-0.1" upper="0.1" effort="50" velocity="1"/>
  </joint>
  <joint name="wrist_fixed" type="fixed">
    <parent link="slider"/><child link="hand"/>
    <origin xyz="0.05 0 -0.02" rpy="0 0.5 0"/>
  </joint>
  <joint name="hip" type="revolute">
    <parent link="base"/><child link="leg"/>
    <origin xyz="0 -0.1 -0.05" rpy="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="10" velocity="5"/>
  </joint>
  <joint name="ankle" type="revolute">
    <parent link="leg"/><child link="foot"/>
    <origin xyz="0 0 -0.3" rpy="0 0 0.2"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="5"/>
  </joint>
</robot>
"""
