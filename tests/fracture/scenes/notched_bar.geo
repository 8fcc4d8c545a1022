// A bar L x H in uniaxial tension with two edge notches of depth a at x = L/2 (the
// ligament H - 2a between them), meshed with structured right triangles of size h, so
// that the vertical edges on x = L/2 form a straight ligament of (H - 2a)/h edges.
// The notches are the lines x = L/2, 0 <= y <= a and H - a <= y <= H (nodes shared;
// cracked before loading). tests/fracture/test_fracture_energy.py.
DefineConstant[
  L = {20, Name "Parameters/L"},
  H = {10, Name "Parameters/H"},
  a = {1, Name "Parameters/a"},
  h = {1, Name "Parameters/h"}
];
nx = Round(0.5 * L / h) + 1;
n1 = Round(a / h) + 1;
n2 = Round((H - 2 * a) / h) + 1;
xs[] = {0, 0.5 * L, L};
ys[] = {0, a, H - a, H};
For i In {0:2}
  For j In {0:3}
    Point(1 + 4 * i + j) = {xs[i], ys[j], 0, h};
  EndFor
EndFor
// vertical lines: column i, segment j (from y_j to y_j+1): 10 + 3 i + j
For i In {0:2}
  For j In {0:2}
    Line(10 + 3 * i + j) = {1 + 4 * i + j, 2 + 4 * i + j};
  EndFor
EndFor
// horizontal lines: strip i (x_i to x_i+1) at level j: 30 + 4 i + j
For i In {0:1}
  For j In {0:3}
    Line(30 + 4 * i + j) = {1 + 4 * i + j, 5 + 4 * i + j};
  EndFor
EndFor
s = 0;
For i In {0:1}
  For j In {0:2}
    Curve Loop(100 + 3 * i + j) = {30 + 4 * i + j, 10 + 3 * (i + 1) + j, -(31 + 4 * i + j), -(10 + 3 * i + j)};
    Plane Surface(100 + 3 * i + j) = {100 + 3 * i + j};
  EndFor
EndFor
Transfinite Curve{30, 31, 32, 33, 34, 35, 36, 37} = nx;
Transfinite Curve{10, 13, 16, 12, 15, 18} = n1;
Transfinite Curve{11, 14, 17} = n2;
Transfinite Surface{100, 101, 102, 103, 104, 105};
Physical Surface("domain") = {100, 101, 102, 103, 104, 105};
Physical Curve("left") = {10, 11, 12};
Physical Curve("right") = {16, 17, 18};
Physical Curve("notch_bottom") = {13};
Physical Curve("notch_top") = {15};
Physical Point("origin") = {1};
