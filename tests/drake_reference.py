"""Independent references on a fresh Drake plant: torques, mass matrices, gravity, distances.

The plant is parsed from the robot's model text (what Drake reads: meshes already resolved)
into a new ``MultibodyPlant``; nothing of drake_mh's compiled kernels is used.
"""

from __future__ import annotations

import numpy as np


class FreshPlant:
    """A new Drake plant (and scene graph) of ``robot``'s model, joints ordered as the robot's.

    Args:
        robot: the drake_mh robot (only its model text, format and joint names are read).
        obstacles: ``[(kind, size, position)]`` world-fixed obstacles for :meth:`min_distance`:
            ``("box", (lx, ly, lz), p)``, ``("sphere", r, p)``, ``("cylinder", (r, length), p)``.
    """

    def __init__(self, robot, obstacles=()):
        from pydrake.geometry import Box, Cylinder, Sphere
        from pydrake.math import RigidTransform
        from pydrake.multibody.parsing import Parser
        from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, CoulombFriction
        from pydrake.multibody.tree import BodyIndex, JointIndex
        from pydrake.systems.framework import DiagramBuilder

        builder = DiagramBuilder()
        plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
        Parser(plant).AddModels(file_contents=robot.model_text,
                                file_type={"mjcf": "xml"}.get(robot.model_format, robot.model_format))
        children = {plant.get_joint(JointIndex(i)).child_body().index() for i in range(plant.num_joints())}
        for i in range(1, plant.num_bodies()):
            body = plant.get_body(BodyIndex(i))
            if body.index() not in children:
                plant.WeldFrames(plant.world_frame(), body.body_frame())
        self.obstacle_ids = set()
        shapes = {"box": lambda s: Box(*s), "sphere": lambda s: Sphere(s), "cylinder": lambda s: Cylinder(*s)}
        for k, (kind, size, position) in enumerate(obstacles):
            gid = plant.RegisterCollisionGeometry(plant.world_body(), RigidTransform(np.asarray(position, float)),
                                                  shapes[kind](size), f"obstacle{k}", CoulombFriction(0.5, 0.5))
            self.obstacle_ids.add(gid)
        plant.Finalize()
        self.plant, self.scene_graph = plant, scene_graph
        self.diagram = builder.Build()
        self.context = self.diagram.CreateDefaultContext()
        self.plant_context = plant.GetMyMutableContextFromRoot(self.context)
        joints = [plant.GetJointByName(n) for n in robot.joint_names]
        self.index = np.array([j.position_start() for j in joints])
        self.damping = np.array([float(np.sum(j.default_damping_vector())) for j in joints])

    def _set(self, q, v=None) -> None:
        x = np.zeros(self.plant.num_positions())
        x[self.index] = q
        self.plant.SetPositions(self.plant_context, x)
        if v is not None:
            xv = np.zeros(self.plant.num_velocities())
            xv[self.index] = v
            self.plant.SetVelocities(self.plant_context, xv)

    def torques(self, Q, V, A) -> np.ndarray:
        """``(N, nq)`` joint torques ``M a + C v - τ_g(q) + damping·v`` [N·m]: Drake's
        ``CalcInverseDynamics`` with no applied forces, minus ``CalcGravityGeneralizedForces``,
        plus the joints' viscous damping (a force element Drake leaves out of inverse dynamics)."""
        from pydrake.multibody.tree import MultibodyForces

        out = []
        for q, v, a in zip(np.atleast_2d(Q), np.atleast_2d(V), np.atleast_2d(A)):
            self._set(q, v)
            acc = np.zeros(self.plant.num_velocities())
            acc[self.index] = a
            tau = self.plant.CalcInverseDynamics(self.plant_context, acc, MultibodyForces(self.plant))
            tau = tau - self.plant.CalcGravityGeneralizedForces(self.plant_context)
            out.append(tau[self.index] + self.damping * v)
        return np.array(out)

    def mass_matrix(self, q) -> np.ndarray:
        """``M(q) (nq, nq)`` from ``CalcMassMatrix``."""
        self._set(q)
        M = self.plant.CalcMassMatrix(self.plant_context)
        return M[np.ix_(self.index, self.index)]

    def gravity(self, q) -> np.ndarray:
        """``(nq,)`` torques holding the arm still: ``-CalcGravityGeneralizedForces``."""
        self._set(q)
        return -self.plant.CalcGravityGeneralizedForces(self.plant_context)[self.index]

    def min_distance(self, q) -> float:
        """Smallest signed distance [m] between the robot and the obstacles at ``q``."""
        self._set(q)
        query = self.scene_graph.get_query_output_port().Eval(self.scene_graph.GetMyContextFromRoot(self.context))
        best = np.inf
        for pair in query.ComputeSignedDistancePairwiseClosestPoints(1.0):
            if (pair.id_A in self.obstacle_ids) != (pair.id_B in self.obstacle_ids):
                best = min(best, pair.distance)
        return float(best)
