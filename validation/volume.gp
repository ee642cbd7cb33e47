# Volume convergence of the ray-cast quadrature (paper Fig. 7).
# Regenerate: gnuplot validation/volume.gp   (from the repository root; data from
# bench/study_volume > validation/volume.dat, see docs/validation.md)
set terminal pngcairo size 800,520 font ",11"
set output "validation/volume.png"
set title "Quadrature volume error vs ray grid n x n"
set xlabel "rays per direction n"
set ylabel "relative volume error"
set logscale xy
set grid
set format y "10^{%L}"
set key top right
plot "validation/volume.dat" using (strcol(1) eq "sphere" ? $2 : 1/0):6 with linespoints pt 7 lc rgb "#1f77b4" title "sphere (exact 4/3 pi)", \
     "validation/volume.dat" using (strcol(1) eq "rounded_cube" ? $2 : 1/0):6 with linespoints pt 5 lc rgb "#d62728" title "rounded\\_cube.iges (divergence theorem)", \
     0.5 * x**-2 with lines dt 2 lc rgb "black" title "n^{-2}"
