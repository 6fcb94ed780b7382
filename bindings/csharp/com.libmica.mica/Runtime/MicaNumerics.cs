// SPDX-License-Identifier: Apache-2.0
// System.Numerics overloads of the object layer: Vector3 for points, directions, forces (m, m/s,
// N, as float) and Quaternion for orientations. libmica takes doubles and quaternions as
// (w, x, y, z); System.Numerics.Quaternion keeps (X, Y, Z, W): the conversion is here, once.
// (UnityEngine.Vector3 converts with `new System.Numerics.Vector3(v.x, v.y, v.z)`; Unity's
// left-handed frame is the caller's to map.)
using System.Numerics;

namespace LibMica
{
    public static class MicaNumerics
    {
        public static double[] ToArray(Vector3 v) { return new double[] { v.X, v.Y, v.Z }; }

        public static Vector3 ToVector3(double[] v) { return new Vector3((float)v[0], (float)v[1], (float)v[2]); }

        /// <summary>(w, x, y, z), as libmica takes it.</summary>
        public static double[] ToArray(Quaternion q) { return new double[] { q.W, q.X, q.Y, q.Z }; }

        /// <summary>From libmica's (w, x, y, z).</summary>
        public static Quaternion ToQuaternion(double[] q)
        {
            return new Quaternion((float)q[1], (float)q[2], (float)q[3], (float)q[0]);
        }

        /// <summary>Gravity, m/s^2.</summary>
        public static void SetGravity(this World world, Vector3 gravity) { world.SetGravity(ToArray(gravity)); }

        /// <summary>A tool created at `position` (m): see World.CreateTool(def, double[]).</summary>
        public static Tool CreateTool(this World world, MicaNative.mica_tool_def def, Vector3 position)
        {
            return world.CreateTool(def, ToArray(position));
        }

        /// <summary>The tool's pose: position (m) and orientation.</summary>
        public static void SetPose(this Tool tool, Vector3 position, Quaternion orientation)
        {
            tool.SetPose(ToArray(position), ToArray(orientation));
        }

        /// <summary>The tool's position (m) with the identity orientation, as SetPose(double[]) does.</summary>
        public static void SetPose(this Tool tool, Vector3 position) { tool.SetPose(ToArray(position)); }

        public static void GetPose(this Tool tool, out Vector3 position, out Quaternion orientation)
        {
            var p = new double[3];
            var q = new double[4];
            tool.GetPose(p, q);
            position = ToVector3(p);
            orientation = ToQuaternion(q);
        }

        /// <summary>Force (N) the bodies put on the tool in the last step.</summary>
        public static Vector3 GetForceVector(this Tool tool) { return ToVector3(tool.GetForce()); }

        /// <summary>Velocity (m/s) of the constrained components.</summary>
        public static void SetVelocity(this Lpc lpc, Vector3 velocity) { lpc.SetVelocity(ToArray(velocity)); }

        public static void SetHandlePose(this Lpc lpc, Vector3 position, Quaternion orientation)
        {
            lpc.SetHandlePose(ToArray(position), ToArray(orientation));
        }

        /// <summary>Reaction force (N) of the last step.</summary>
        public static Vector3 GetReactionVector(this Lpc lpc) { return ToVector3(lpc.GetReaction()); }

        /// <summary>Holds the nodes within `radius` (m) of `center` on a handle (following `tool` if given).</summary>
        public static Lpc Grab(this Body body, Vector3 center, double radius, Tool tool = null)
        {
            return body.Grab(ToArray(center), radius, tool);
        }

        public static int[] SelectNodesByPlane(this Body body, Vector3 point, Vector3 normal, double tolerance, bool useRest)
        {
            return body.SelectNodesByPlane(ToArray(point), ToArray(normal), tolerance, useRest);
        }
    }
}
