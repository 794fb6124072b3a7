# Written by hbirl; run `gnuplot /tmp/cal100/calibration.gp` to redraw.
$d0 << EOD
0.0370652 0.166667 0.0869551 0.295778 0.05 48
0.147582 0.166667 0.0667868 0.358531 0.15 24
0.240668 0.285714 0.138139 0.499564 0.25 21
0.358379 0.296296 0.15853 0.484807 0.35 27
0.461246 0.490909 0.363768 0.619237 0.45 55
0.537376 0.4375 0.32294 0.559138 0.55 64
0.644616 0.55 0.398291 0.692947 0.65 40
0.754115 0.674419 0.525162 0.795067 0.75 43
0.856957 0.814815 0.691641 0.896173 0.85 54
0.976798 0.883929 0.835363 0.919548 0.95 224
EOD
$d1 << EOD
0.0353514 0.444444 0.188779 0.733349 0.05 9
0.140778 0.25 0.0714792 0.590725 0.15 8
0.242312 0.5 0.0945312 0.905469 0.25 2
0.347018 0.5 0.150039 0.849961 0.35 4
0.45186 0.666667 0.299993 0.903229 0.45 6
0.564487 0.777778 0.452589 0.936775 0.55 9
0.614276 0.666667 0.20766 0.938508 0.65 3
0.752434 0.785714 0.524108 0.924286 0.75 14
0.854959 0.88 0.700442 0.958332 0.85 25
0.986945 0.984615 0.969939 0.992184 0.95 520
EOD
set terminal pngcairo size 1000,1100 noenhanced font 'sans,11'
set output '/tmp/cal100/calibration.png'
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
plot x title 'calibrated' lc rgb '#888888' dt 2, $d0 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#d95f02' title 'from observations (ECE 0.079, AUROC 0.821)', $d1 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#1b9e77' title 'from truth (ECE 0.019, AUROC 0.896)'
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
set output '/tmp/cal100/calibration.svg'
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
plot x title 'calibrated' lc rgb '#888888' dt 2, $d0 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#d95f02' title 'from observations (ECE 0.079, AUROC 0.821)', $d1 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#1b9e77' title 'from truth (ECE 0.019, AUROC 0.896)'
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
