// SPDX-License-Identifier: Apache-2.0
// The few UnityEngine types the documented C# samples use, so that test_doc_samples.py compiles
// and runs them on Mono outside Unity: Debug writes to the console; a MonoBehaviour is a plain
// object whose Start, FixedUpdate and OnDestroy the test calls in Unity's order; a Mesh keeps what
// it is given; a GameObject holds components.
namespace UnityEngine
{
    public struct Vector3
    {
        public float x, y, z;
        public Vector3(float x, float y, float z) { this.x = x; this.y = y; this.z = z; }
        public static Vector3 one { get { return new Vector3(1, 1, 1); } }
        public static Vector3 operator *(Vector3 v, float s) { return new Vector3(v.x * s, v.y * s, v.z * s); }
    }

    public struct Color
    {
        public static readonly Color red = new Color();
    }

    public class Transform
    {
        public Vector3 position;
    }

    public class Component
    {
    }

    public class GameObject
    {
        readonly System.Collections.Generic.List<Component> components = new System.Collections.Generic.List<Component>();
        public T AddComponent<T>() where T : Component, new()
        {
            var c = new T();
            components.Add(c);
            return c;
        }
        public T GetComponent<T>() where T : Component
        {
            foreach (var c in components)
                if (c is T) return (T)c;
            return null;
        }
    }

    public class MonoBehaviour : Component
    {
        public bool enabled = true;
        public GameObject gameObject = new GameObject();
    }

    public class Mesh
    {
        public Vector3[] vertices;
        public Vector3[] normals;
        public int[] triangles;
        public void MarkDynamic() { }
        public void RecalculateBounds() { }
    }

    public class MeshFilter : Component
    {
        public Mesh mesh;
    }

    public class MeshRenderer : Component
    {
    }

    public static class Debug
    {
        public static void Log(object message) { System.Console.WriteLine(message); }
        public static void LogError(object message) { System.Console.Error.WriteLine(message); }
    }

    public static class Time
    {
        public static float fixedDeltaTime = 0.02f; // Unity's default
    }

    public static class Gizmos
    {
        public static Color color;
        public static void DrawCube(Vector3 center, Vector3 size) { }
    }
}
