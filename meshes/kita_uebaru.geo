// Moving layer of the Kita-Uebaru landslide model (Edo (2016), §4.3.2, Fig. 4.4-4.5), our profile.
// Edo (2016) gives the slope length (237 m along the ground surface) and the greatest
// vertical depth of the moving layer (15.8 m) but not the profile; we build it as:
//   ground surface  a straight slope of `slope` degrees from the crown (0, H) to the toe
//                   (Lx, 0), Lx = length cos(slope), H = Lx tan(slope);
//   slip surface    two planes: a steep upper one from the crown down to the kink, where
//                   the layer is deepest (`depth`), and a flat lower one at `base` degrees
//                   from the kink to the toe (a two-wedge slide: the layer cannot move as a
//                   rigid body, it must shear above the kink, which is where its internal
//                   friction angle matters);
//   weak band       the lower `weak` fraction of the depth (lower density, Fig. 4.5).
// Physical groups: "upper" and "weak" (the moving layer, surfaces) and "bed" (curve): the
// immobile ground the layer slides on, the slip surface extended upwards by the scarp
// (the upper plane, `scarp` m further horizontally) and downwards by a flat plain of
// `plain` m for the runout.
DefineConstant[ slope = 8, depth = 15.8, length = 237, base = -20, weak = 0.2, h = 0.6,
                scarp = 30, plain = 300 ];
Lx = length * Cos(slope * Pi / 180);
H = Lx * Tan(slope * Pi / 180);
tb = Tan(base * Pi / 180);
lower = depth / (H / Lx - tb);  // horizontal length of the lower plane
If (lower >= Lx || lower <= 0)
  Error("kita_uebaru.geo: slope %g, depth %g and base %g give no kink", slope, depth, base);
EndIf
xk = Lx - lower;
yk = tb * lower;
crown = newp; Point(crown) = {0, H, 0, h};
toe = newp; Point(toe) = {Lx, 0, 0, h};
kink = newp; Point(kink) = {xk, yk, 0, h};
yg = H * (1 - xk / Lx);
band = newp; Point(band) = {xk, yk + weak * (yg - yk), 0, h};
top = newc; Line(top) = {toe, crown};
s1 = newc; Line(s1) = {crown, kink};
s2 = newc; Line(s2) = {kink, toe};
b1 = newc; Line(b1) = {crown, band};
b2 = newc; Line(b2) = {band, toe};
cw = newcl; Curve Loop(cw) = {s1, s2, -b2, -b1};
sw = news; Plane Surface(sw) = {cw};
cu = newcl; Curve Loop(cu) = {b1, b2, top};
su = news; Plane Surface(su) = {cu};
// the bed outside the moving layer: the scarp above the crown, the plain beyond the toe
t1 = (H - yk) / xk;
ps = newp; Point(ps) = {-scarp, H + scarp * t1, 0, 4 * h};
pe = newp; Point(pe) = {Lx + plain, 0, 0, 4 * h};
lscarp = newc; Line(lscarp) = {ps, crown};
lplain = newc; Line(lplain) = {toe, pe};
Physical Surface("weak") = {sw};
Physical Surface("upper") = {su};
Physical Curve("bed") = {lscarp, s1, s2, lplain};
