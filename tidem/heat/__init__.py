"""Heat and reaction heat, set-up and analytic side: the explicit updates' stability limits
(limits), Schlünder's packet model, heated mesh walls (drum_heat), impact conduction and
reacting particles (reactions). Layer 3: may import gas/, walls/ and layer 0; not particles/."""
