// SPDX-License-Identifier: Apache-2.0
// Plays the Unity package's PressCube sample as Unity would (Start, FixedUpdate each physics
// step, OnDestroy) with its probe 5 mm above the cube, then down 1 mm a step, and prints the
// vertical force on the sphere as the docs' samples do ("step k: F N").
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
        Call(sample, "OnDestroy");
    }
}
