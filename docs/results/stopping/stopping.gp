# Written by hbirl; run `gnuplot docs/results/stopping/stopping.gp` to redraw.
$curve << EOD
1 0.366667 0.385401
2 0.4 0.42469
3 0.366667 0.409185
4 0.433333 0.434805
5 0.45 0.475718
6 0.517241 0.496525
7 0.555556 0.55795
8 0.58 0.556072
9 0.545455 0.562558
10 0.511628 0.570224
11 0.534884 0.561417
12 0.512195 0.546082
13 0.583333 0.576936
14 0.571429 0.570578
15 0.545455 0.541695
16 0.53125 0.572061
17 0.612903 0.565313
18 0.533333 0.566873
19 0.482759 0.617303
20 0.517241 0.602802
21 0.571429 0.589753
22 0.555556 0.611969
23 0.6 0.580059
24 0.625 0.585163
25 0.681818 0.633317
26 0.65 0.605036
27 0.647059 0.651328
28 0.647059 0.633081
29 0.666667 0.629241
30 0.666667 0.647169
31 0.666667 0.631657
32 0.7 0.634642
33 0.875 0.770179
34 0.75 0.695604
35 0.833333 0.759366
36 0.8 0.74705
37 0.8 0.747282
EOD
$stop0 << EOD
12 1
3 1
11 1
7 1
5 1
10 1
5 1
5 1
3 1
38 1
3 1
3 1
13 1
23 1
8 1
19 1
7 1
EOD
$stop1 << EOD
12 1
3 1
11 1
7 1
5 1
6 1
3 1
3 1
3 1
18 1
26 1
8 1
23 1
11 1
EOD
set terminal pngcairo size 1000,900 noenhanced font 'sans,11'
set output 'docs/results/stopping/stopping.png'
set multiplot layout 2,1
set grid
set key bottom right
set xlabel 'demonstrations seen'
set yrange [0:1.05]
set title 'Random tasks while they are watched: share right and mean confidence'
plot $curve using 1:2 with linespoints lw 2 pt 7 lc rgb '#1b9e77' title 'share right (tasks with >= n demonstrations)', $curve using 1:3 with linespoints lw 2 pt 5 lc rgb '#7570b3' title 'mean confidence'
set title 'Where the rule stopped (3 in a row): demonstrations at the stop'
set ylabel 'tasks'
set yrange [0:*]
set style fill solid 0.6
set boxwidth 0.4
plot $stop0 using ($1 + 0):(1) smooth frequency with boxes lc rgb '#d95f02' title 'p = 0.90', $stop1 using ($1 + 0.4):(1) smooth frequency with boxes lc rgb '#e7298a' title 'p = 0.95'
unset multiplot
set terminal svg size 1000,900 noenhanced font 'sans,11' background rgb 'white'
set output 'docs/results/stopping/stopping.svg'
set multiplot layout 2,1
set grid
set key bottom right
set xlabel 'demonstrations seen'
set yrange [0:1.05]
set title 'Random tasks while they are watched: share right and mean confidence'
plot $curve using 1:2 with linespoints lw 2 pt 7 lc rgb '#1b9e77' title 'share right (tasks with >= n demonstrations)', $curve using 1:3 with linespoints lw 2 pt 5 lc rgb '#7570b3' title 'mean confidence'
set title 'Where the rule stopped (3 in a row): demonstrations at the stop'
set ylabel 'tasks'
set yrange [0:*]
set style fill solid 0.6
set boxwidth 0.4
plot $stop0 using ($1 + 0):(1) smooth frequency with boxes lc rgb '#d95f02' title 'p = 0.90', $stop1 using ($1 + 0.4):(1) smooth frequency with boxes lc rgb '#e7298a' title 'p = 0.95'
unset multiplot
unset output
