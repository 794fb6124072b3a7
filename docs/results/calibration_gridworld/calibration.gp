# Written by hbirl; run `gnuplot docs/results/calibration_gridworld/calibration.gp` to redraw.
$d0 << EOD
0.495675 1 0.206549 1 0.45 1
0.557752 1 0.34238 1 0.55 2
0.652648 1 0.34238 1 0.65 2
0.735677 0.666667 0.20766 0.938508 0.75 3
0.828787 1 0.438503 1 0.85 3
0.996637 0.976331 0.940731 0.990758 0.95 169
EOD
$d1 << EOD
0.999948 1 0.979105 1 0.95 180
EOD
set terminal pngcairo size 1000,1100 noenhanced font 'sans,11'
set output 'docs/results/calibration_gridworld/calibration.png'
set multiplot layout 2,1
set size 1,0.7
set origin 0,0.3
set grid
set key left top
set xrange [0:1]
set yrange [0:1]
set xlabel 'confidence (mean in bin)'
set ylabel 'share right'
set title 'Reliability: share of runs within 5% of the optimal value against the confidence (95% Wilson)'
plot x title 'calibrated' lc rgb '#888888' dt 2, $d0 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#d95f02' title 'from observations (ECE 0.035, AUROC 0.736)', $d1 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#1b9e77' title 'from truth (ECE 0.000, AUROC 0.500)'
set size 1,0.3
set origin 0,0
set title 'Runs per confidence bin'
set xlabel 'confidence'
set ylabel 'runs'
set yrange [0:*]
set style fill solid 0.6
set boxwidth 0.04
plot $d0 using ($5-0.02):6 with boxes lc rgb '#d95f02' title 'observations', $d1 using ($5+0.02):6 with boxes lc rgb '#1b9e77' title 'truth'
unset multiplot
set terminal svg size 1000,1100 noenhanced font 'sans,11' background rgb 'white'
set output 'docs/results/calibration_gridworld/calibration.svg'
set multiplot layout 2,1
set size 1,0.7
set origin 0,0.3
set grid
set key left top
set xrange [0:1]
set yrange [0:1]
set xlabel 'confidence (mean in bin)'
set ylabel 'share right'
set title 'Reliability: share of runs within 5% of the optimal value against the confidence (95% Wilson)'
plot x title 'calibrated' lc rgb '#888888' dt 2, $d0 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#d95f02' title 'from observations (ECE 0.035, AUROC 0.736)', $d1 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#1b9e77' title 'from truth (ECE 0.000, AUROC 0.500)'
set size 1,0.3
set origin 0,0
set title 'Runs per confidence bin'
set xlabel 'confidence'
set ylabel 'runs'
set yrange [0:*]
set style fill solid 0.6
set boxwidth 0.04
plot $d0 using ($5-0.02):6 with boxes lc rgb '#d95f02' title 'observations', $d1 using ($5+0.02):6 with boxes lc rgb '#1b9e77' title 'truth'
unset multiplot
unset output
