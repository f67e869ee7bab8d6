// The fixtures gmsh_box_*.msh, written by Gmsh 4.8.4 (Debian package gmsh) from this file:
//   gmsh gmsh_box.geo -3 -format msh41 -bin -save_parametric -o gmsh_box_41_binary.msh
//   gmsh gmsh_box.geo -3 -format msh41 -save_parametric -o gmsh_box_41_ascii.msh
//   gmsh gmsh_box.geo -3 -format msh22 -bin -o gmsh_box_22_binary.msh
//   gmsh gmsh_box.geo -3 -format msh22 -o gmsh_box_22_ascii.msh
// Tetrahedra, boundary triangles of one face, a line and a point (physical groups), all
// sections Gmsh writes ($PhysicalNames, $Entities, parametric nodes).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 0.5, 0.25};
Physical Volume("solid") = {1};
Physical Surface("bottom") = {5};
Mesh.MeshSizeMax = 0.5;
Mesh.MeshSizeMin = 0.2;
Physical Curve("edge") = {1};
Physical Point("corner") = {1};
