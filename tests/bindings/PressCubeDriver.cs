// SPDX-License-Identifier: Apache-2.0
// Plays the Unity package's PressCube sample as Unity would (Start, FixedUpdate each physics
// step, OnDestroy) with its probe 5 mm above the cube, then down 1 mm a step, and prints the
// vertical force on the sphere as the docs' samples do ("step k: F N"), then how far the centre of
// the embedded sheet went down and its normal, as the mesh the sample drew has them.
using System.Reflection;
using UnityEngine;

static class PressCubeDriver
{
    const BindingFlags Private = BindingFlags.Instance | BindingFlags.NonPublic;

    static void Call(PressCube sample, string method) { typeof(PressCube).GetMethod(method, Private).Invoke(sample, null); }

    static void Main()
    {
        var sample = new PressCube { Probe = new Transform { position = new Vector3(0, 0.125f, 0) } };
        Call(sample, "Start");
        var sphere = (LibMica.Tool)typeof(PressCube).GetField("sphere", Private).GetValue(sample);
        for (int k = 0; k < 30; ++k)
        {
            sample.Probe.position = new Vector3(0, 0.125f - 0.001f * k, 0);
            Call(sample, "FixedUpdate");
            System.Console.WriteLine("step {0}: {1:F3} N", k, sphere.GetForce()[1]);
        }
        var mesh = sample.gameObject.GetComponent<MeshFilter>().mesh;
        var centre = mesh.vertices.Length / 2;   // the middle vertex of an odd grid
        var p = mesh.vertices[centre];
        var n = mesh.normals[centre];
        System.Console.WriteLine("sheet centre: {0:F2} mm down, normal ({1:F2}, {2:F2}, {3:F2})", 1e3 * (0.1 - p.y), n.x, n.y, n.z);
        if (!(0.1 - p.y > 1e-3) || !(n.y > 0.5)) throw new System.Exception("the sheet did not follow the cube");
        Call(sample, "OnDestroy");
    }
}
