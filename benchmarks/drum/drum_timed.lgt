# LIGGGHTS 3.8.0: the timed part of shared/bench/peers/drum.lgt, from a data file of a settled state
# (drum_peer.py data), so that LIGGGHTS and tidem time the same steps from the same state.
# usage: liggghts -in drum_timed.lgt -var data drum.data -var nwarm 2000 -var nsteps 5000
atom_style      granular
atom_modify     map array
boundary        f f f
newton          off
communicate     single vel yes
units           si
processors      * 1 *

read_data       ${data}

neighbor        0.0001 bin
neigh_modify    delay 0

fix  m1 all property/global youngsModulus peratomtype 1.e7
fix  m2 all property/global poissonsRatio peratomtype 0.3
fix  m3 all property/global coefficientRestitution peratomtypepair 1 0.5
fix  m4 all property/global coefficientFriction peratomtypepair 1 0.5

pair_style      gran model hertz tangential history
pair_coeff      * *

fix  cad all mesh/surface file drum.stl type 1
fix  walls all wall/gran model hertz tangential history mesh n_meshes 1 meshes cad
fix  ends all wall/gran model hertz tangential history primitive type 1 yplane 0.0
fix  ende all wall/gran model hertz tangential history primitive type 1 yplane 0.015
fix  gravi all gravity 9.81 vector 0.0 0.0 -1.0

fix  integr all nve/sphere
compute cn all contact/atom
compute cnave all reduce ave c_cn
thermo_style    custom step atoms ke c_cnave
thermo          1000
thermo_modify   lost ignore norm no

timestep        1e-6
fix  turn all move/mesh mesh cad rotate origin 0. 0. 0. axis 0. 1. 0. period 2.0943951
run             ${nwarm}
run             ${nsteps}
