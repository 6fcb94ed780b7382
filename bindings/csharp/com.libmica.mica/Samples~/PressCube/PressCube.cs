// SPDX-License-Identifier: Apache-2.0
// A soft cube fixed at its base and a sphere you move with a Transform (drag it in the Scene view,
// or parent it to a tracked stylus): the cube deforms and the force the tissue puts on the sphere
// is logged and drawn. A fine sheet over the cube's top face (SheetVertices^2 vertices) is embedded
// in the cube (Body.Embed) and drawn as the GameObject's mesh: after each step its positions and
// normals come from the tets. Put this on an empty GameObject, give it a material (a
// MeshRenderer's), assign `Probe` (any Transform) and press Play. Needs libmica.so in Assets/Plugins/x86_64/ (Linux x86-64; see the package's README).
// Units: libmica is SI (m, N); 1 Unity unit is taken as 1 m. Unity's frame is left-handed: z is
// flipped on the way in and out so the cube's base stays at y = 0.
using LibMica;
using UnityEngine;

public sealed class PressCube : MonoBehaviour
{
    public Transform Probe;              // the sphere's centre follows it
    public float ProbeRadius = 0.02f;    // m
    public float YoungsModulus = 1e4f;   // Pa
    public int CellsPerSide = 8;
    public int SheetVertices = 41;       // along each side of the embedded sheet

    World world;
    Body cube;
    LibMica.Tool sphere;
    double[] positions;
    Embedding sheet;                     // the render mesh, bound to the cube's tets once
    double[] sheetXyz, sheetNormals;     // libmica's frame, updated in place after each step
    Vector3[] vertices, normals;         // Unity's frame, handed to the mesh
    Mesh mesh;

    void Start()
    {
        if (Probe == null)
        {
            Debug.LogError("PressCube: assign Probe, the Transform the sphere follows");
            enabled = false;
            return;
        }
        var def = Mica.WorldDef();   // the haptic default: MICA with the factored sweep
        def.time_budget_ms = 10;     // a step never takes longer than a frame's share
        world = new World(def, (level, text) => Debug.Log("libmica: " + text));
        var body = Mica.BodyDef();
        body.youngs_modulus = YoungsModulus;
        body.rayleigh_alpha = 2;
        var n = CellsPerSide;
        cube = world.CreateBox(new[] { -0.05, 0, -0.05 }, new[] { 0.05, 0.1, 0.05 }, new[] { n, n, n }, 5, body);
        cube.AddLpc(cube.SelectNodesByPlane(System.Numerics.Vector3.Zero, System.Numerics.Vector3.UnitY, 1e-9, true),
                    Mica.LpcDef());
        var tool = Mica.ToolDef();
        tool.radius = ProbeRadius;
        // Made where the probe is: SetPose moves the sphere along a sweep from its last pose, so a
        // sphere made at the origin, inside the cube, would drag the tissue up to the probe.
        sphere = world.CreateTool(tool, ToMica(Probe.position));
        MakeSheet();
    }

    // The sheet: SheetVertices^2 vertices on the top face (y = 0.1 m), two triangles a square,
    // counter-clockwise seen from above in libmica's frame.
    void MakeSheet()
    {
        var n = SheetVertices;
        sheetXyz = new double[3 * n * n];
        sheetNormals = new double[3 * n * n];
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j)
            {
                var k = 3 * (i * n + j);
                sheetXyz[k] = -0.05 + 0.1 * i / (n - 1);
                sheetXyz[k + 1] = 0.1;
                sheetXyz[k + 2] = -0.05 + 0.1 * j / (n - 1);
            }
        var triangles = new int[6 * (n - 1) * (n - 1)];
        var unity = new int[triangles.Length];   // Unity's winding: mirrored by the z flip
        var t = 0;
        for (int i = 0; i + 1 < n; ++i)
            for (int j = 0; j + 1 < n; ++j)
            {
                int a = i * n + j, b = a + n, c = a + n + 1, d = a + 1;
                foreach (var v in new[] { a, d, c, a, c, b }) triangles[t++] = v;
            }
        for (int k = 0; k < triangles.Length; k += 3)
        {
            unity[k] = triangles[k];
            unity[k + 1] = triangles[k + 2];
            unity[k + 2] = triangles[k + 1];
        }
        sheet = cube.Embed(sheetXyz, triangles);
        sheet.Update(sheetXyz, sheetNormals);
        vertices = new Vector3[n * n];
        normals = new Vector3[n * n];
        mesh = new Mesh();
        mesh.MarkDynamic();
        ToUnity();
        mesh.triangles = unity;
        var filter = gameObject.GetComponent<MeshFilter>();
        if (filter == null) filter = gameObject.AddComponent<MeshFilter>();
        filter.mesh = mesh;
        if (gameObject.GetComponent<MeshRenderer>() == null) gameObject.AddComponent<MeshRenderer>();
    }

    // The sheet's positions and normals into the mesh, z flipped.
    void ToUnity()
    {
        for (int i = 0; i < vertices.Length; ++i)
        {
            vertices[i] = new Vector3((float)sheetXyz[3 * i], (float)sheetXyz[3 * i + 1], -(float)sheetXyz[3 * i + 2]);
            normals[i] = new Vector3((float)sheetNormals[3 * i], (float)sheetNormals[3 * i + 1], -(float)sheetNormals[3 * i + 2]);
        }
        mesh.vertices = vertices;
        mesh.normals = normals;
        mesh.RecalculateBounds();
    }

    // Unity's frame is left-handed: z flips between it and libmica's.
    static System.Numerics.Vector3 ToMica(Vector3 p) { return new System.Numerics.Vector3(p.x, p.y, -p.z); }

    void FixedUpdate()
    {
        if (world == null) return;
        if (Probe != null) sphere.SetPose(ToMica(Probe.position));
        world.Step(Time.fixedDeltaTime);
        positions = cube.GetPositions(positions);
        sheet.Update(sheetXyz, sheetNormals);   // allocates nothing
        ToUnity();
        var f = sphere.GetForceVector();
        if (f.Length() > 0) Debug.Log(string.Format("force on the probe: {0:F3} N", f.Length()));
    }

    void OnDrawGizmos()
    {
        if (positions == null) return;
        Gizmos.color = Color.red;
        for (int i = 0; i < positions.Length / 3; ++i)
            Gizmos.DrawCube(new Vector3((float)positions[3 * i], (float)positions[3 * i + 1], -(float)positions[3 * i + 2]),
                            Vector3.one * 0.002f);
    }

    void OnDestroy()
    {
        if (world != null) world.Dispose();
        world = null;
    }
}
