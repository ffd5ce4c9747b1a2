"""The grains: sizes and start positions (placement, fill_pockets), pours, initial overlaps, the
storage order, the contact laws' parameter tables (contact_params) and time scales (timestep).
Layer 3: may import gas/, walls/ and layer 0; not heat/."""
