// spi_master: a small SPI mode-0 master (CPOL = 0, CPHA = 0), one byte per request.
//
// Mode 0 as the ICM-42688-P expects it (datasheet DS-000347, "SPI interface"; docs/GYRO.md): SCLK
// idles low, the slave samples MOSI on the rising SCLK edge and changes MISO after the falling
// edge, bytes are sent MSB first, CS is active low and held low over a whole transaction.
//
// Interface: when busy_o is low, start_i for one cycle sends tx_i; last_i says it is the last byte
// of the transaction (CS goes high after it). done_o pulses for one cycle with the received byte in
// rx_o (held until the next byte ends). Bytes of one transaction follow each other with CS low.
//
// Timing: every SCLK half period is HALF = CLK_HZ / (2 * SCLK_HZ) clock cycles (at least 1). CS
// falls HALF cycles before the first rising edge (CS setup), rises HALF cycles after the last
// falling edge (CS hold) and then stays high for at least HALF cycles (CS deselect) before the next
// transaction. MOSI changes only with the falling edge (or at start, while SCLK is low); MISO is
// sampled in the last cycle of each high phase, just before the falling edge.
//
// Assumptions: rst_i synchronous, active high; start_i is ignored while busy_o is high.
// Guarantees (proven by k-induction in the FORMAL block): SCLK is low whenever CS is high; MOSI
// never changes while SCLK is high; each byte has exactly 8 rising edges and MOSI carries tx_i MSB
// first at them; rx_o is the MISO bits sampled at the 8 high phases, MSB first; exactly one done_o
// per accepted start.
`resetall
`timescale 1ns / 1ps
`default_nettype none

`include "omniloc_regs.vh"

module spi_master #(
    parameter integer CLK_HZ = `OMNILOC_BOARD_CLOCK_HZ,
    parameter integer SCLK_HZ = `OMNILOC_GYRO_SCLK_HZ
) (
    input  wire       clk_i,
    input  wire       rst_i,
    input  wire       start_i,
    input  wire [7:0] tx_i,
    input  wire       last_i,
    output wire       busy_o,
    output wire       done_o,
    output wire [7:0] rx_o,
    output wire       sclk_o,
    output wire       mosi_o,
    input  wire       miso_i,
    output wire       cs_n_o
);

localparam integer HALF_RAW = CLK_HZ / (2 * SCLK_HZ);
localparam integer HALF = HALF_RAW < 1 ? 1 : HALF_RAW;
localparam integer DIV_W = HALF > 1 ? $clog2(HALF) : 1;
localparam integer HALF_M1 = HALF - 1;
localparam [DIV_W-1:0] DIV_LOAD = HALF_M1[DIV_W-1:0];

localparam [1:0] S_IDLE = 2'd0;   // CS as the last byte left it, waiting for start_i
localparam [1:0] S_XFER = 2'd1;   // 16 half periods of SCLK
localparam [1:0] S_HOLD = 2'd2;   // CS hold after the last byte, CS still low
localparam [1:0] S_GAP  = 2'd3;   // CS high for at least one half period

reg [1:0]       state_q;
reg [DIV_W-1:0] div_q;
reg [3:0]       half_q;      // half period within the byte: even = SCLK low, odd = SCLK high
reg [7:0]       sr_q;        // shifts tx out at bit 7 and MISO in at bit 0
reg             last_q;
reg             cs_n_q;
reg             sclk_q;
reg             done_q;

assign busy_o = state_q != S_IDLE;
assign done_o = done_q;
assign rx_o = sr_q;
assign sclk_o = sclk_q;
assign mosi_o = sr_q[7];
assign cs_n_o = cs_n_q;

wire div_end = div_q == {DIV_W{1'b0}};

always @(posedge clk_i) begin
    if (rst_i) begin
        state_q <= S_IDLE;
        div_q <= DIV_LOAD;
        half_q <= 4'd0;
        last_q <= 1'b0;
        cs_n_q <= 1'b1;
        sclk_q <= 1'b0;
        done_q <= 1'b0;
    end else begin
        done_q <= 1'b0;
        if (state_q != S_IDLE) div_q <= div_end ? DIV_LOAD : div_q - 1'b1;
        case (state_q)
            S_IDLE: if (start_i) begin
                state_q <= S_XFER;
                div_q <= DIV_LOAD;
                half_q <= 4'd0;
                last_q <= last_i;
                cs_n_q <= 1'b0;
            end
            S_XFER: if (div_end) begin
                half_q <= half_q + 4'd1;
                sclk_q <= ~half_q[0];
                if (half_q == 4'd15) begin
                    done_q <= 1'b1;
                    state_q <= last_q ? S_HOLD : S_IDLE;
                end
            end
            S_HOLD: if (div_end) begin
                cs_n_q <= 1'b1;
                state_q <= S_GAP;
            end
            default: if (div_end) state_q <= S_IDLE;   // S_GAP
        endcase
    end
end

// The shift register is pure data: loaded at start, shifted at each falling edge.
always @(posedge clk_i) begin
    if (state_q == S_IDLE && start_i) sr_q <= tx_i;
    else if (state_q == S_XFER && div_end && half_q[0]) sr_q <= {sr_q[6:0], miso_i};
end

`ifdef FORMAL
reg f_past_valid = 1'b0;
always @(posedge clk_i) f_past_valid <= 1'b1;
initial assume (rst_i);

wire f_start = !rst_i && state_q == S_IDLE && start_i;

// Shadow of the byte being sent, the MISO bits seen in high phases and the rising-edge count.
reg [7:0] f_tx = 8'd0;
reg [7:0] f_rx = 8'd0;
reg [3:0] f_rises = 4'd0;
reg       f_open = 1'b0;     // a start was accepted and its done_o has not come yet
always @(posedge clk_i) begin
    if (rst_i) begin
        f_open <= 1'b0;
        f_rises <= 4'd0;
    end else begin
        if (f_start) begin
            f_tx <= tx_i;
            f_rises <= 4'd0;
            f_open <= 1'b1;
        end
        if (state_q == S_XFER && div_end && !half_q[0]) f_rises <= f_rises + 4'd1;
        if (state_q == S_XFER && div_end && half_q[0]) f_rx <= {f_rx[6:0], miso_i};
        if (done_q && !f_start) f_open <= 1'b0;
    end
end

// Index of the bit sent at the latest rising edge (f_rises counts it already): 8 - rises.
wire [3:0] f_bit_full = 4'd8 - f_rises;
wire [2:0] f_bit = f_bit_full[2:0];

always @(*) begin
    if (f_past_valid && !rst_i) begin
        // Mode 0: SCLK idles low; it only runs in a transfer.
        if (cs_n_q) assert (!sclk_q);
        if (state_q != S_XFER) assert (!sclk_q);
        if (state_q == S_XFER) assert (!cs_n_q);
        if (state_q == S_GAP) assert (cs_n_q);
        if (state_q == S_HOLD) assert (!cs_n_q);
        assert (div_q <= DIV_LOAD);
        // Invariants tying the shadow to the state (they make the induction close).
        if (state_q == S_XFER) begin
            assert (f_open);
            assert (sclk_q == half_q[0]);
            assert (f_rises == {1'b0, half_q[3:1]} + {3'b0, half_q[0]});
            // The shift register: the unsent tx bits on top, the received bits below.
            assert (sr_q == ((f_tx << half_q[3:1]) | (f_rx & ~(8'hFF << half_q[3:1]))));
        end
        if (state_q == S_IDLE || state_q == S_GAP || state_q == S_HOLD) assert (!f_open || done_q);
        if (done_q) assert (f_rises == 4'd8 && rx_o == f_rx);
    end
end

always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i) begin
        // MOSI never changes while SCLK is high (slave samples on the rising edge).
        if (sclk_q) assert (mosi_o == $past(mosi_o));
        // At each rising edge MOSI carries the next bit of tx_i, MSB first.
        if (sclk_q && !$past(sclk_q)) assert (mosi_o == f_tx[f_bit]);
        // One done per accepted start, only after the 8th rising edge.
        if (done_q) assert ($past(state_q) == S_XFER);
        // CS falls only at an accepted start.
        if ($past(cs_n_q) && !cs_n_q) assert ($past(f_start));
    end
end

// Covers: a byte 0xA5 received; a two-byte transaction ending with CS high again.
reg [1:0] f_bytes = 2'd0;
always @(posedge clk_i) begin
    if (rst_i || cs_n_q) f_bytes <= 2'd0;
    else if (done_q && f_bytes != 2'd3) f_bytes <= f_bytes + 2'd1;
end
always @(posedge clk_i) begin
    if (f_past_valid && !rst_i) begin
        cover (done_q && rx_o == 8'hA5);
        cover ($past(f_bytes) == 2'd2 && cs_n_q && !$past(cs_n_q));
    end
end
`endif

endmodule

`resetall
